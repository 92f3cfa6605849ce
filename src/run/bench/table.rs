//! What the bench's two sections share in `bench.md` and `bench.csv`: the CSV's columns, and
//! how a peak memory is written.

/// `bench.csv`'s columns. The last four came with the whole stockings, after the sweep's so
/// that a reader of those still finds them where it did: `bottom` (`ankle` for the sweep, whose
/// bundled scene ends there; `toe`), `heel` (empty where there is none to choose),
/// `whole_seconds` (the whole run, whole stockings only) and `reach_m` (toe tip to the nearest
/// yarn point).
pub(super) const CSV_HEADER: &str =
    "leg,wales,courses,points,solver,tolerance,seconds,iterations,residual,\
                          max_move,converged,max_penetration_m,peak_memory_bytes,density_error,\
                          rms_distance_m,bottom,heel,whole_seconds,reach_m\n";

/// A peak memory in MiB, `n/a` where the system did not say.
pub(super) fn mib(bytes: Option<u64>) -> String {
    bytes.map_or("n/a".into(), |b| format!("{:.0}", b as f64 / 1048576.0))
}
