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

/// The (sample, case) pairs a costly matrix runs: every pair in the long profile; in the
/// default suite each case once and each sample at least once, dealt round-robin so each case
/// meets a different sample (every sample still runs through the test's other checks).
pub fn pairs<S: Clone, C: Clone>(samples: &[S], cases: &[C]) -> Vec<(S, C)> {
    if enabled() {
        return samples
            .iter()
            .flat_map(|s| cases.iter().map(move |c| (s.clone(), c.clone())))
            .collect();
    }
    let n = samples.len().max(cases.len());
    if samples.is_empty() || cases.is_empty() {
        return Vec::new();
    }
    (0..n)
        .map(|i| {
            (
                samples[i % samples.len()].clone(),
                cases[i % cases.len()].clone(),
            )
        })
        .collect()
}
