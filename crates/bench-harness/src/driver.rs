//! Running one scene through one backend, in this process: the loop behind
//! `surftrack run` (and behind every child process of the benchmarks).
//!
//! Each step: the flow proposes positions from the tracker's mesh, the tracker advances,
//! the new mesh is validated (layers 1–3 of `validate()`, the exact intersection layer on
//! request), frames are written every `every` steps. The run stops at the first failure
//! and says which of the 2024 paper's failure kinds it was (§9.6): an error from
//! `advance`, a panic (caught here, so the record is still written), an invalid frame, or
//! the triangle cap (the memory guard). Time-outs and crashes are the caller's to detect:
//! the benchmarks run this loop in a child process under a watchdog
//! ([`crate::isolate`]).

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::ProgressBar;
use mesh_core::LabeledMesh;
use mesh_core::validate::{ValidateOptions, validate};
use surftrack::{Backend, BackendError, SurfaceTracker, make_tracker_from};
use tracing::{debug, info, warn};

use crate::options::RunOptions;
use crate::preservation::{Preservation, Reference, measure};
use crate::record::{
    EventCounts, Failure, FailureReason, FrameRecord, LabelVolume, MeshSummary, RUN_SCHEMA,
    RunRecord, SceneParams, StepRecord, add_stage_seconds,
};
use crate::scenes::rolling::{self, RollingMotion};
use crate::scenes::{SceneError, SceneOptions, build_tracked_with};

/// Longest failure message kept in a record (validation reports can list thousands of
/// offenders; the first lines say enough).
const MAX_MESSAGE: usize = 2000;

/// Fraction of a flow's stability limit taken as the step when the limit is below the
/// scene's time step (mean curvature flow).
const STABLE_FRACTION: f64 = 0.9;

/// What to run and where to put the output.
#[derive(Debug, Clone)]
pub struct RunConfig {
    /// Scene name.
    pub scene: String,
    /// Scene parameters.
    pub options: SceneOptions,
    /// Backend.
    pub backend: Backend,
    /// Steps (default: the scene's).
    pub steps: Option<usize>,
    /// Time step (default: the scene's).
    pub dt: Option<f64>,
    /// Write a frame every this many steps (and the initial and last ones); 0 = none.
    pub every: usize,
    /// Directory for frames (`frame_0000.ply`, …); required when `every > 0`.
    pub out: Option<PathBuf>,
    /// Write ASCII instead of binary PLY frames.
    pub ascii: bool,
    /// Fail with [`FailureReason::Memory`] when a step leaves more triangles than this.
    pub max_triangles: Option<usize>,
    /// Also run the exact self-intersection layer of `validate()` on every step.
    pub check_intersections: bool,
    /// Every backend and flow option ([`RunOptions`]); recorded in the run record.
    pub run_options: RunOptions,
    /// The scene parameters as given, recorded for replays.
    pub scene_params: SceneParams,
}

/// Why a run could not even start (a failing tracker is not an error: it is a record).
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scene could not be built.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A parameter is out of range.
    #[error("{0}")]
    Config(String),
    /// A frame could not be written.
    #[error("cannot write frame {path}: {message}")]
    Frame {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        message: String,
    },
}

/// The text of a panic payload.
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "panic with a non-string payload".to_string()
    }
}

/// Cuts a message to [`MAX_MESSAGE`] characters.
fn truncate(mut message: String) -> String {
    if message.len() > MAX_MESSAGE {
        let mut cut = MAX_MESSAGE;
        while !message.is_char_boundary(cut) {
            cut -= 1;
        }
        message.truncate(cut);
        message.push_str(" …");
    }
    message
}

/// Writes one frame, named by its step.
fn write_frame(
    mesh: &LabeledMesh,
    dir: &Path,
    step: usize,
    suffix: &str,
    ascii: bool,
) -> Result<FrameRecord, RunError> {
    use mesh_core::io::{PlyFormat, write_ply};
    let file = format!("frame_{step:04}{suffix}.ply");
    let path = dir.join(&file);
    let frame_error = |message: String| RunError::Frame {
        path: path.clone(),
        message,
    };
    let handle = std::fs::File::create(&path).map_err(|e| frame_error(e.to_string()))?;
    let format = if ascii {
        PlyFormat::Ascii
    } else {
        PlyFormat::BinaryLittleEndian
    };
    write_ply(mesh, std::io::BufWriter::new(handle), format)
        .map_err(|e| frame_error(e.to_string()))?;
    Ok(FrameRecord { step, file })
}

/// Runs a scene: builds it, makes the tracker, steps, validates, writes frames. Returns
/// the record of the run, successful or not; `Err` only when the run could not start or
/// a frame could not be written.
pub fn run_scene(config: &RunConfig, progress: &ProgressBar) -> Result<RunRecord, RunError> {
    let options = config.run_options.backend_options();
    run_scene_with(config, progress, |mesh| {
        make_tracker_from(config.backend, mesh, &options)
    })
}

/// [`run_scene`] with another way to make the tracker (a simulator's own backend, or a
/// test double); `config.backend` then only names it in the record.
pub fn run_scene_with(
    config: &RunConfig,
    progress: &ProgressBar,
    make: impl FnOnce(LabeledMesh) -> Result<Box<dyn SurfaceTracker>, BackendError>,
) -> Result<RunRecord, RunError> {
    let scene = build_tracked_with(&config.scene, &config.options, &config.run_options.flow)?;
    let steps = config.steps.unwrap_or(scene.steps);
    // The rolling scene's motion spans a fixed duration, whatever the number of steps.
    let scene_dt = match (config.dt, scene.name) {
        (Some(dt), _) => dt,
        (None, "rolling") => rolling::DURATION / steps.max(1) as f64,
        (None, _) => scene.dt,
    };
    if !(scene_dt.is_finite() && scene_dt > 0.0) {
        return Err(RunError::Config(match config.dt {
            Some(_) => format!("--dt must be finite and positive, got {scene_dt}"),
            // Derived from the scene: say so, not name an option the user never gave.
            None => format!(
                "scene `{}` derived a time step of {scene_dt} (give one with --dt)",
                config.scene
            ),
        }));
    }
    let frames_dir = match (&config.out, config.every) {
        (_, 0) => None,
        (Some(dir), _) => Some(dir.clone()),
        (None, _) => {
            return Err(RunError::Config(
                "writing frames (--every > 0) needs an output directory".into(),
            ));
        }
    };
    if let Some(dir) = &frames_dir {
        std::fs::create_dir_all(dir).map_err(|e| RunError::Frame {
            path: dir.clone(),
            message: e.to_string(),
        })?;
    }
    let validate_options = ValidateOptions {
        intersections: config.check_intersections,
        max_listed: 5,
        ..ValidateOptions::default()
    };
    let initial_report = validate(&scene.mesh, &validate_options);
    let mut record = RunRecord {
        schema: RUN_SCHEMA.to_string(),
        // A user-mesh scene is named by its flow spec, which a replay needs.
        scene: if config.scene.starts_with(crate::scenes::user::PREFIX) {
            config.scene.clone()
        } else {
            scene.name.to_string()
        },
        tracker: config.backend.name().to_string(),
        seed: config.options.seed,
        count: scene.count,
        dt: scene_dt,
        steps,
        steps_completed: 0,
        success: false,
        failure: None,
        wall_seconds: 0.0,
        peak_triangles: scene.mesh.num_triangles(),
        events: EventCounts::default(),
        stage_seconds: Vec::new(),
        initial: MeshSummary {
            vertices: scene.mesh.num_vertices(),
            triangles: scene.mesh.num_triangles(),
            valid: initial_report.is_valid(),
        },
        frames: Vec::new(),
        per_step: Vec::with_capacity(steps),
        options: Some(config.run_options.clone()),
        scene_params: Some(config.scene_params.clone()),
        threads: rayon::current_num_threads(),
        volumes: Vec::new(),
        preservation: None,
        final_digest: None,
        peak_rss_mib: None,
        mib_per_million_triangles: None,
    };
    let initial_mesh = scene.mesh.clone();
    let _span =
        tracing::info_span!("run", scene = scene.name, tracker = config.backend.name()).entered();
    info!(
        vertices = record.initial.vertices,
        triangles = record.initial.triangles,
        steps,
        dt = scene_dt,
        "scene built"
    );
    let start = Instant::now();
    let fail = |record: &mut RunRecord, reason, message: String, step| {
        if reason == FailureReason::Unavailable {
            info!("{message}");
        } else {
            warn!(%reason, step, "{message}");
        }
        record.failure = Some(Failure {
            reason,
            message: truncate(message),
            step,
        });
    };

    let made = catch_unwind(AssertUnwindSafe(|| make(scene.mesh)));
    let mut tracker: Box<dyn SurfaceTracker> = match made {
        Ok(Ok(tracker)) => tracker,
        Ok(Err(err @ BackendError::Unavailable { .. })) => {
            fail(
                &mut record,
                FailureReason::Unavailable,
                err.to_string(),
                None,
            );
            record.wall_seconds = start.elapsed().as_secs_f64();
            return Ok(record);
        }
        Ok(Err(err)) => {
            fail(&mut record, FailureReason::Error, err.to_string(), None);
            record.wall_seconds = start.elapsed().as_secs_f64();
            return Ok(record);
        }
        Err(payload) => {
            let message = format!("constructing the tracker: {}", panic_message(&*payload));
            fail(&mut record, FailureReason::Panic, message, None);
            record.wall_seconds = start.elapsed().as_secs_f64();
            return Ok(record);
        }
    };
    if let Some(dir) = &frames_dir {
        record
            .frames
            .push(write_frame(tracker.mesh(), dir, 0, "", config.ascii)?);
    }

    progress.set_length(steps as u64);
    let mut t = 0.0;
    for step in 1..=steps {
        let dt = match scene.flow.max_stable_dt(tracker.mesh()) {
            Some(limit) if limit > 0.0 && STABLE_FRACTION * limit < scene_dt => {
                STABLE_FRACTION * limit
            }
            _ => scene_dt,
        };
        let step_start = Instant::now();
        let outcome = catch_unwind(AssertUnwindSafe(|| {
            let proposed = scene.flow.propose(tracker.mesh(), t, dt);
            tracker.advance(&proposed)
        }));
        let seconds = step_start.elapsed().as_secs_f64();
        let report = match outcome {
            Ok(Ok(report)) => report,
            Ok(Err(err)) => {
                fail(
                    &mut record,
                    FailureReason::Error,
                    err.to_string(),
                    Some(step),
                );
                break;
            }
            Err(payload) => {
                let message = panic_message(&*payload);
                fail(&mut record, FailureReason::Panic, message, Some(step));
                break;
            }
        };
        let mut step_record = StepRecord::from_report(step, t, dt, seconds, &report);
        t += dt;
        let mesh = tracker.mesh();
        // The tracker's own counts may lag behind its mesh; the mesh is the truth.
        step_record.triangles = mesh.num_triangles();
        step_record.vertices = mesh.num_vertices();
        let check = validate(mesh, &validate_options);
        step_record.valid = check.is_valid();
        record.events.add(&step_record.events);
        for s in &step_record.stages {
            add_stage_seconds(&mut record.stage_seconds, &s.stage, s.seconds);
        }
        record.peak_triangles = record.peak_triangles.max(step_record.triangles);
        debug!(
            step,
            seconds,
            triangles = step_record.triangles,
            valid = step_record.valid,
            "step"
        );
        let triangles = step_record.triangles;
        let valid = step_record.valid;
        record.per_step.push(step_record);
        record.steps_completed = step;
        progress.set_message(format!("{triangles} triangles"));
        progress.inc(1);
        if !valid {
            if let Some(dir) = &frames_dir {
                record
                    .frames
                    .push(write_frame(mesh, dir, step, "_invalid", config.ascii)?);
            }
            fail(
                &mut record,
                FailureReason::Invalid,
                check.to_string(),
                Some(step),
            );
            break;
        }
        if let Some(cap) = config.max_triangles.filter(|&cap| triangles > cap) {
            let message = format!("{triangles} triangles after the step, above the cap of {cap}");
            fail(&mut record, FailureReason::Memory, message, Some(step));
            break;
        }
        if let Some(dir) = &frames_dir
            && (step % config.every == 0 || step == steps)
        {
            record
                .frames
                .push(write_frame(mesh, dir, step, "", config.ascii)?);
        }
    }
    record.wall_seconds = start.elapsed().as_secs_f64();
    record.success = record.failure.is_none() && record.steps_completed == steps;
    let last = tracker.mesh();
    record.volumes = label_volumes(&initial_mesh, last);
    record.preservation = Some(preservation(
        scene.name,
        &config.options,
        &initial_mesh,
        last,
        t,
    ));
    record.final_digest = Some(mesh_digest(last));
    info!(
        success = record.success,
        seconds = record.wall_seconds,
        "run finished"
    );
    Ok(record)
}

/// Per-label volumes of the initial and the last mesh (label 0 excluded).
fn label_volumes(initial: &LabeledMesh, last: &LabeledMesh) -> Vec<LabelVolume> {
    let before = mesh_core::geometry::label_volumes(initial);
    let after = mesh_core::geometry::label_volumes(last);
    let mut labels: Vec<mesh_core::Label> = before.keys().chain(after.keys()).copied().collect();
    labels.sort_unstable();
    labels.dedup();
    labels
        .into_iter()
        .filter(|l| *l != mesh_core::Label::OUTSIDE)
        .map(|l| {
            let initial = before.get(&l).copied().unwrap_or(0.0);
            let last = after.get(&l).copied().unwrap_or(0.0);
            LabelVolume {
                label: l.raw(),
                initial,
                last,
                relative_drift: if initial != 0.0 {
                    (last - initial) / initial
                } else {
                    0.0
                },
            }
        })
        .collect()
}

/// Feature preservation of the last mesh at time `t` ([`crate::preservation`]): against
/// the rigidly moved original for `rolling`, against the unmoved original otherwise.
fn preservation(
    scene: &str,
    options: &SceneOptions,
    initial: &LabeledMesh,
    last: &LabeledMesh,
    t: f64,
) -> Preservation {
    let (lo, hi) = initial.vertices().map(|v| initial.position(v)).fold(
        (glam::DVec3::INFINITY, glam::DVec3::NEG_INFINITY),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    );
    let size = if lo.is_finite() && hi.is_finite() {
        (hi - lo).length()
    } else {
        1.0
    };
    let tolerance = 1e-9 * size.max(f64::MIN_POSITIVE);
    let search = 2.0 * mesh_core::remesh::improve::mean_edge_length(initial);
    let reference = if scene == "rolling" {
        let motion = RollingMotion::new(options.radius.unwrap_or(rolling::RADIUS));
        let margin = 0.25 * motion.radius;
        let mut expected = initial.positions().to_vec();
        let mut contact = vec![false; initial.vertex_capacity()];
        for v in initial.vertices() {
            let p0 = initial.position(v);
            expected[v.idx()] = motion.place(RollingMotion::sphere_of(p0), p0, t);
            contact[v.idx()] = motion.in_contact_zone(p0, margin);
        }
        Reference {
            initial,
            expected,
            contact: Some(contact),
        }
    } else {
        Reference {
            initial,
            expected: initial.positions().to_vec(),
            contact: None,
        }
    };
    measure(&reference, last, tolerance, search)
}

/// FNV-1a over the live vertices (slot, position bits) and triangles (slot, vertices,
/// labels): equal digests mean bit-identical meshes.
pub fn mesh_digest(mesh: &LabeledMesh) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: u64| {
        for b in x.to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for v in mesh.vertices() {
        eat(v.idx() as u64);
        for c in mesh.position(v).to_array() {
            eat(c.to_bits());
        }
    }
    for t in mesh.triangles() {
        eat(t.idx() as u64);
        for v in mesh.tri(t) {
            eat(v.idx() as u64);
        }
        for l in mesh.labels(t) {
            eat(u64::from(l.raw()));
        }
    }
    format!("{h:016x}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::{StepReport, TrackError, check_proposal};

    /// How the test tracker misbehaves, and at which step (1-based).
    #[derive(Clone, Copy)]
    enum Misbehave {
        Never,
        ErrorAt(usize),
        PanicAt(usize),
        NanAt(usize),
    }

    /// A test double: moves every vertex where it is told, no topology handling.
    struct Follow {
        mesh: LabeledMesh,
        step: usize,
        misbehave: Misbehave,
    }

    impl SurfaceTracker for Follow {
        fn name(&self) -> &str {
            "follow"
        }
        fn mesh(&self) -> &LabeledMesh {
            &self.mesh
        }
        fn advance(&mut self, proposed: &[glam::DVec3]) -> Result<StepReport, TrackError> {
            check_proposal(&self.mesh, proposed)?;
            self.step += 1;
            match self.misbehave {
                Misbehave::ErrorAt(k) if k == self.step => {
                    return Err(TrackError::StageFailed {
                        stage: "follow",
                        reason: "asked to fail".into(),
                    });
                }
                Misbehave::PanicAt(k) if k == self.step => panic!("asked to panic"),
                _ => {}
            }
            let vertices: Vec<_> = self.mesh.vertices().collect();
            for v in vertices {
                self.mesh.set_position(v, proposed[v.idx()]);
            }
            if matches!(self.misbehave, Misbehave::NanAt(k) if k == self.step) {
                self.mesh
                    .set_position(mesh_core::VertexId::new(0), glam::DVec3::NAN);
            }
            let mut report = StepReport {
                vertices: self.mesh.num_vertices(),
                triangles: self.mesh.num_triangles(),
                substeps: 1,
                ..StepReport::default()
            };
            report.time_stage("follow", std::time::Duration::from_millis(1));
            report.events.remeshing_edits = 2;
            Ok(report)
        }
    }

    fn config(steps: usize, every: usize, out: Option<PathBuf>) -> RunConfig {
        RunConfig {
            scene: "spheres".into(),
            options: crate::scenes::smoke_options("spheres"),
            backend: Backend::Grid,
            steps: Some(steps),
            dt: None,
            every,
            out,
            ascii: false,
            max_triangles: None,
            check_intersections: true,
            run_options: RunOptions::default(),
            scene_params: SceneParams::default(),
        }
    }

    fn run_with(config: &RunConfig, misbehave: Misbehave) -> RunRecord {
        run_scene_with(config, &ProgressBar::hidden(), |mesh| {
            Ok(Box::new(Follow {
                mesh,
                step: 0,
                misbehave,
            }))
        })
        .unwrap()
    }

    #[test]
    fn a_clean_run_records_every_step_and_writes_valid_frames() {
        let dir = tempfile::tempdir().unwrap();
        let config = config(3, 2, Some(dir.path().to_path_buf()));
        let record = run_with(&config, Misbehave::Never);
        assert!(record.success, "{:?}", record.failure);
        assert_eq!(record.steps_completed, 3);
        assert_eq!(record.per_step.len(), 3);
        assert!(record.per_step.iter().all(|s| s.valid && s.triangles > 0));
        assert_eq!(record.events.remeshing_edits, 6);
        assert_eq!(record.stage_seconds.len(), 1);
        assert!((record.stage_seconds[0].seconds - 0.003).abs() < 1e-12);
        // Frames: the initial mesh, every 2nd step, and the last.
        let steps: Vec<usize> = record.frames.iter().map(|f| f.step).collect();
        assert_eq!(steps, vec![0, 2, 3]);
        for frame in &record.frames {
            let mesh = mesh_core::io::read_mesh(&dir.path().join(&frame.file)).unwrap();
            let report = validate(&mesh, &ValidateOptions::with_intersections());
            assert!(report.is_valid(), "{}: {report}", frame.file);
            assert_eq!(mesh.num_triangles(), record.initial.triangles);
        }
        // The spheres grew: the last frame is not the first.
        let first = mesh_core::io::read_mesh(&dir.path().join("frame_0000.ply")).unwrap();
        let last = mesh_core::io::read_mesh(&dir.path().join("frame_0003.ply")).unwrap();
        assert_ne!(first.positions(), last.positions());
    }

    #[test]
    fn failures_are_classified_and_stop_the_run() {
        let c = config(4, 0, None);
        let cases = [
            (Misbehave::ErrorAt(2), FailureReason::Error, 1),
            (Misbehave::PanicAt(3), FailureReason::Panic, 2),
            (Misbehave::NanAt(1), FailureReason::Invalid, 1),
        ];
        for (misbehave, reason, completed) in cases {
            let record = run_with(&c, misbehave);
            assert!(!record.success);
            let failure = record.failure.as_ref().unwrap();
            assert_eq!(failure.reason, reason, "{}", failure.message);
            assert_eq!(record.steps_completed, completed);
        }
        let capped = RunConfig {
            max_triangles: Some(10),
            ..c
        };
        let record = run_with(&capped, Misbehave::Never);
        assert_eq!(record.failure.unwrap().reason, FailureReason::Memory);
        assert_eq!(record.steps_completed, 1);
    }

    #[test]
    fn an_unavailable_backend_gives_a_failed_record_not_an_error() {
        let record = run_scene_with(&config(2, 0, None), &ProgressBar::hidden(), |_| {
            Err(BackendError::Unavailable {
                backend: Backend::Collision,
                reason: "not built",
            })
        })
        .unwrap();
        assert!(!record.success);
        assert_eq!(record.steps_completed, 0);
        let failure = record.failure.unwrap();
        assert_eq!(failure.reason, FailureReason::Unavailable);
        assert!(failure.message.contains("not built"));
        assert!(record.initial.valid && record.initial.triangles > 0);
    }

    #[test]
    fn bad_configurations_are_errors() {
        let hidden = ProgressBar::hidden();
        let negative = RunConfig {
            dt: Some(-1.0),
            ..config(1, 0, None)
        };
        assert!(matches!(
            run_scene(&negative, &hidden),
            Err(RunError::Config(_))
        ));
        assert!(matches!(
            run_scene(&config(1, 1, None), &hidden),
            Err(RunError::Config(_))
        ));
        let unknown = RunConfig {
            scene: "nope".into(),
            ..config(1, 0, None)
        };
        assert!(matches!(
            run_scene(&unknown, &hidden),
            Err(RunError::Scene(_))
        ));
    }

    #[test]
    fn long_messages_are_cut_on_a_character_boundary() {
        let long = "é".repeat(MAX_MESSAGE);
        let cut = truncate(long);
        assert!(cut.len() <= MAX_MESSAGE + " …".len());
        assert!(cut.ends_with(" …"));
    }
}
