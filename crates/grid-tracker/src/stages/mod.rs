//! The pipeline stages, one module each, in the order of the paper.
//!
//! 1. [`grid`] — §4: the sparse background grid ([`grid::build_grid`]);
//! 2. [`materials`] — §5: material vectors by exact ray casting
//!    ([`materials::assign_materials`]);
//! 3. [`flaws`] — §6: the flawed region ([`flaws::detect_flaws`]).

pub mod cut;
pub mod flaws;
pub mod grid;
pub mod labels;
pub mod materials;
pub mod rebuild;
pub mod transfer;
