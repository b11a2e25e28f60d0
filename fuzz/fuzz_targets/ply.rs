//! Fuzz target `ply`: see `surftrack_fuzz::check_ply` for the property checked.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| surftrack_fuzz::check_ply(data));
