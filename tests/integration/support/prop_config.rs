//! The one proptest configuration of the property and fuzz tests (the integration tests', and the
//! library's unit tests', which include this file by path): a fixed seed, so every run tries the
//! same cases (no entropy anywhere, STYLE 9); no failure files, since a failure found becomes a
//! named regression test instead; and `PROPTEST_CASES` in the environment, when set, replacing
//! each test's own case count, for longer runs. `KNITFIT_FUZZ_SHARD=k` (k ≥ 1) runs shard k: the
//! seed plus k, a fixed stream of cases of its own, so long runs on several machines or nights
//! (`tools/fuzz_long.sh`) add up to new cases instead of repeating shard 0's.

use proptest::test_runner::{Config, RngSeed};

/// The seed of every property and fuzz test.
const SEED: u64 = 0x6b6e_6974_6669_7421;

/// A configuration running `default_cases` cases (ten times as many in the long profile,
/// `KNITFIT_LONG=1`), or `PROPTEST_CASES` where that is set.
pub fn config(default_cases: u32) -> Config {
    let long = std::env::var_os("KNITFIT_LONG").is_some_and(|v| v != "0");
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(if long { 10 } else { 1 } * default_cases);
    let shard = std::env::var("KNITFIT_FUZZ_SHARD")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
        .unwrap_or(0);
    Config {
        cases,
        // Properties that assume their setting (a start outside the skin, say) reject some
        // cases; allow that at any count.
        max_global_rejects: cases.saturating_mul(4).max(1024),
        rng_seed: RngSeed::Fixed(SEED.wrapping_add(shard)),
        failure_persistence: None,
        ..Config::default()
    }
}
