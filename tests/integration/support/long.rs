//! The long profile: `KNITFIT_LONG=1 cargo test --release -- --include-ignored`
//! (docs/TESTING.md). Each long case is a longer version of one the default suite runs (a finer
//! grid, the real stitch count, more fuzz cases), for before a release and after a change to the
//! solver or the contact; CI runs the shorter one.

/// Whether `KNITFIT_LONG` is set to anything but `0`: run the long cases too.
pub fn enabled() -> bool {
    std::env::var_os("KNITFIT_LONG").is_some_and(|v| v != "0")
}
