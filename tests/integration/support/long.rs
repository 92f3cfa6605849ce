//! The long profile: `KNITFIT_LONG=1 cargo test --release -- --include-ignored`
//! (docs/TESTING.md). Each long case is a longer version of one the default suite runs (a finer
//! grid, the real stitch count, more fuzz cases), for before a release and after a change to the
//! solver or the contact; CI runs the shorter one.

/// Whether `KNITFIT_LONG` is set to anything but `0`: run the long cases too.
pub fn enabled() -> bool {
    std::env::var_os("KNITFIT_LONG").is_some_and(|v| v != "0")
}

/// The samples a costly hard case runs on: all of them in the long profile; in the default
/// suite the two legs made most differently among the quick ones, a MakeHuman leg with its foot
/// and a low-poly game leg. The whole body and the heavy hips take two to three times as long to
/// fit and take no other path through the case's code.
pub fn samples<T: AsRef<std::path::Path>>(all: impl IntoIterator<Item = T>) -> Vec<T> {
    const KEPT: [&str; 2] = ["makehuman_leg_foot.glb", "lowpoly_leg.glb"];
    let long = enabled();
    all.into_iter()
        .filter(|leg| {
            long || leg
                .as_ref()
                .file_name()
                .is_some_and(|name| KEPT.iter().any(|kept| name == *kept))
        })
        .collect()
}
