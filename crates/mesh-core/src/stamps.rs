//! [`Stamps`]: "seen in this pass" flags over dense ids, cleared in O(1) per pass.
//!
//! Why: a guard check looks at a few dozen triangles or vertices out of millions and must
//! visit each once. Sorting what it found to drop repeats, or clearing a flag per id, costs
//! more than the check; a stamp per id holding the number of the pass that last saw it
//! makes "seen?" one comparison and a new pass one increment.

/// Per id, the number of the pass that last saw it (see the [module doc](self)).
#[derive(Clone, Debug, Default)]
pub struct Stamps {
    stamps: Vec<u32>,
    pass: u32,
}

impl Stamps {
    /// Starts a new pass over ids below `len`: every id is unseen. The stamps are cleared
    /// only when the pass number wraps around.
    pub fn next_pass(&mut self, len: usize) {
        if self.stamps.len() < len {
            self.stamps.resize(len, 0);
        }
        self.pass = self.pass.wrapping_add(1);
        if self.pass == 0 {
            self.stamps.fill(0);
            self.pass = 1;
        }
    }

    /// Marks `id` seen in this pass; false when it already was. An id beyond the pass's
    /// `len` is reported as a first sight every time: a caller is never told to skip
    /// something it was not told about before.
    #[inline]
    pub fn first_sight(&mut self, id: usize) -> bool {
        match self.stamps.get_mut(id) {
            Some(s) if *s == self.pass => false,
            Some(s) => {
                *s = self.pass;
                true
            }
            None => true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_id_is_a_first_sight_once_per_pass() {
        let mut s = Stamps::default();
        s.next_pass(4);
        assert!(s.first_sight(2));
        assert!(!s.first_sight(2));
        assert!(s.first_sight(3));
        assert!(
            s.first_sight(9) && s.first_sight(9),
            "beyond len: never skipped"
        );
        s.next_pass(4);
        assert!(s.first_sight(2), "a new pass forgets the old one");
        // Wrapping the pass number clears the stamps instead of reusing an old number.
        s.pass = u32::MAX;
        s.stamps[1] = 1;
        s.next_pass(4);
        assert_eq!(s.pass, 1);
        assert!(s.first_sight(1));
    }
}
