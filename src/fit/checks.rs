//! What a finished fit must be, besides converged, before it is called done: no yarn point
//! inside the skin, no yarn left through the skin by the penetration fix, and a stitch density
//! that changes smoothly over the skin. A stocking's density changes a few times over from ankle
//! to thigh, never tenfold between two neighbouring vertices: a jump like that is fabric folded
//! through itself or torn across a broken mesh, not a fit. A fit that fails a check still has its
//! products (its files show what went wrong) but is not done: `knitfit fit` warns, naming the
//! check, and exits 4.

use serde::{Deserialize, Serialize};

use crate::leg::Leg;
use crate::post::penetration::PenetrationStats;

/// The largest ratio of stitch density between two neighbouring covered leg vertices of a
/// sound fit. The samples' worst is under 2 at every grid; an order of magnitude is a fault.
pub const MAX_NEIGHBOUR_DENSITY_RATIO: f64 = 10.0;

/// The checks a finished fit passed or failed, for the report.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitChecks {
    /// How deep the deepest yarn point lies inside the skin after the exact contact pass,
    /// metres (the report's `max_penetration_m`): 0 in a sound fit.
    pub yarn_inside_skin_m: f64,
    /// Yarn pieces that still cross the skin after the penetration fix; `null` where the fix
    /// did not run.
    pub yarn_pieces_crossing: Option<usize>,
    /// Where one of them lies, world space, metres; `null` where none does.
    #[serde(default)]
    pub yarn_crossing_at_m: Option<[f64; 3]>,
    /// The stitch density check; `null` where the leg's fields were not measured.
    pub density: Option<DensityJumps>,
}

/// How stitch density changes between neighbouring leg vertices the stocking covers.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DensityJumps {
    /// Leg edges, both ends covered, whose ends' densities differ more than
    /// [`MAX_NEIGHBOUR_DENSITY_RATIO`] times.
    pub edges_over_limit: usize,
    /// The largest ratio over the covered edges (1 where there are none).
    pub worst_ratio: f64,
    /// The middle of the edge with the worst ratio, world space, metres.
    pub worst_at_m: Option<[f64; 3]>,
}

impl FitChecks {
    /// The checks of a fit on `leg` whose deepest yarn point is `max_penetration_m` inside the
    /// skin, with `density` per leg vertex (empty where not measured) and the penetration fix's
    /// counters, where it ran.
    pub fn of(
        leg: &Leg,
        max_penetration_m: f64,
        density: &[f64],
        fix: Option<&PenetrationStats>,
    ) -> FitChecks {
        FitChecks {
            yarn_inside_skin_m: max_penetration_m,
            yarn_pieces_crossing: fix.map(|f| f.still_crossing),
            yarn_crossing_at_m: fix.and_then(|f| f.still_crossing_at_m),
            density: (density.len() == leg.positions.len()).then(|| density_jumps(leg, density)),
        }
    }

    /// What failed, one phrase each; empty when the fit passed.
    pub fn failures(&self) -> Vec<String> {
        let mut failed = Vec::new();
        if self.yarn_inside_skin_m > 0.0 {
            failed.push(format!(
                "yarn points lie up to {:.3} mm inside the skin",
                1e3 * self.yarn_inside_skin_m
            ));
        }
        if let Some(n @ 1..) = self.yarn_pieces_crossing {
            let at = (self.yarn_crossing_at_m).map_or(String::new(), |[x, y, z]| {
                format!(" (one at ({x:.3}, {y:.3}, {z:.3}) m)")
            });
            failed.push(format!(
                "{n} yarn piece{} still cross{} the skin after the penetration fix{at}",
                if n == 1 { "" } else { "s" },
                if n == 1 { "es" } else { "" }
            ));
        }
        if let Some(d) = self.density.as_ref().filter(|d| d.edges_over_limit > 0) {
            let at = d.worst_at_m.map_or(String::new(), |[x, y, z]| {
                format!(
                    " (worst {:.0}× at ({x:.3}, {y:.3}, {z:.3}) m)",
                    d.worst_ratio
                )
            });
            failed.push(format!(
                "stitch density changes more than {MAX_NEIGHBOUR_DENSITY_RATIO:.0}-fold between \
                 neighbouring leg vertices on {} edge{}{at}: the fabric folds or tears there",
                d.edges_over_limit,
                if d.edges_over_limit == 1 { "" } else { "s" }
            ));
        }
        failed
    }

    /// True when every check that ran passed.
    pub fn passed(&self) -> bool {
        self.failures().is_empty()
    }
}

/// The density ratios over `leg`'s edges whose two ends `density` covers (> 0).
fn density_jumps(leg: &Leg, density: &[f64]) -> DensityJumps {
    let mut jumps = DensityJumps {
        edges_over_limit: 0,
        worst_ratio: 1.0,
        worst_at_m: None,
    };
    let mut edges: Vec<(usize, usize)> = (leg.triangles.iter())
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b) as usize, a.max(b) as usize))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    for (a, b) in edges {
        let (da, db) = (density[a], density[b]);
        if da <= 0.0 || db <= 0.0 {
            continue;
        }
        let ratio = da.max(db) / da.min(db);
        jumps.edges_over_limit += usize::from(ratio > MAX_NEIGHBOUR_DENSITY_RATIO);
        if ratio > jumps.worst_ratio {
            jumps.worst_ratio = ratio;
            let middle = nalgebra::center(&leg.positions[a], &leg.positions[b]);
            jumps.worst_at_m = Some(middle.coords.into());
        }
    }
    jumps
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cylinder() -> Leg {
        Leg::round(0.05, 0.4, 24, 20)
    }

    #[test]
    fn a_smooth_density_passes_and_a_tenfold_step_between_neighbours_fails_where_it_is() {
        let leg = cylinder();
        // Density rising fourfold from bottom to top: smooth, passes.
        let smooth: Vec<f64> = (leg.positions.iter())
            .map(|p| 100.0 + 750.0 * p.y)
            .collect();
        let checks = FitChecks::of(&leg, 0.0, &smooth, Some(&PenetrationStats::default()));
        assert!(checks.passed(), "{checks:?}");
        let d = checks.density.as_ref().unwrap();
        assert!(d.worst_ratio < 1.2, "{d:?}");
        // One vertex at a hundredth of its neighbours': every edge around it fails, and the worst
        // is next to it.
        let mut dented = smooth.clone();
        let v = leg.positions.len() / 2;
        dented[v] /= 100.0;
        let checks = FitChecks::of(&leg, 0.0, &dented, None);
        let d = checks.density.as_ref().unwrap();
        let around = (leg.triangles.iter())
            .filter(|t| t.contains(&(v as u32)))
            .count();
        assert!(
            d.edges_over_limit >= 4 && d.edges_over_limit <= around,
            "{d:?}"
        );
        assert!(d.worst_ratio > 90.0, "{d:?}");
        let at = nalgebra::Point3::from(d.worst_at_m.unwrap());
        assert!(
            (at - leg.positions[v]).norm() < 0.05,
            "{at} vs {}",
            leg.positions[v]
        );
        let failures = checks.failures();
        assert_eq!(failures.len(), 1, "{failures:?}");
        assert!(failures[0].contains("more than 10-fold"), "{}", failures[0]);
    }

    #[test]
    fn uncovered_vertices_and_an_unmeasured_leg_are_not_jumps() {
        let leg = cylinder();
        // The stocking's edge: covered vertices next to bare ones (density 0).
        let edge: Vec<f64> = (leg.positions.iter())
            .map(|p| if p.y < 0.2 { 300.0 } else { 0.0 })
            .collect();
        assert!(FitChecks::of(&leg, 0.0, &edge, None).passed());
        let unmeasured = FitChecks::of(&leg, 0.0, &[], None);
        assert_eq!(unmeasured.density, None);
        assert!(unmeasured.passed());
    }

    #[test]
    fn yarn_left_through_the_skin_fails() {
        let fix = PenetrationStats {
            still_crossing: 3,
            ..PenetrationStats::default()
        };
        let checks = FitChecks::of(&cylinder(), 0.0, &[], Some(&fix));
        assert_eq!(checks.yarn_pieces_crossing, Some(3));
        assert_eq!(
            checks.failures(),
            ["3 yarn pieces still cross the skin after the penetration fix"]
        );
        // Where the fix says one lies, the check says it too.
        let fix = PenetrationStats {
            still_crossing_at_m: Some([0.1, -0.42, 0.03]),
            ..fix
        };
        let checks = FitChecks::of(&cylinder(), 0.0, &[], Some(&fix));
        assert_eq!(
            checks.failures(),
            [
                "3 yarn pieces still cross the skin after the penetration fix (one at (0.100, \
              -0.420, 0.030) m)"
            ]
        );
    }

    #[test]
    fn a_yarn_point_inside_the_skin_fails() {
        let checks = FitChecks::of(&cylinder(), 3.5e-4, &[], None);
        assert_eq!(
            checks.failures(),
            ["yarn points lie up to 0.350 mm inside the skin"]
        );
        assert!(FitChecks::of(&cylinder(), 0.0, &[], None).passed());
    }
}
