//! Fuzz target `obj`: see `surftrack_fuzz::check_obj` for the property checked.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| surftrack_fuzz::check_obj(data));
