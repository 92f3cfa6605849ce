//! The fast solver: coarse-to-fine relaxation, the "nested iteration" half of full multigrid
//! (Brandt, "Multi-level adaptive solutions to boundary-value problems", 1977).
//!
//! The knit is first relaxed on a grid with about half the wales and half the courses of the
//! one asked for (and that on a grid half as fine again, down to [`COARSEST`] points a side;
//! a stocking to the toe on the real stitch count's own levels with no more wales where it has
//! them, [`grid_sizes_following`]: its foot rests where the coarse levels leave it).
//! A coarse grid stands for the same stocking: its rest lengths are twice as long, so the same
//! relaxed circumference and length. Its rest state is interpolated (bilinearly, around the
//! closed courses and along the wales by relaxed fabric) onto the next finer grid, the
//! constraints put any interpolated point that fell inside the leg back out ([`Constraints::settle`]), and the
//! accelerated iteration ([`super::accelerated`]) continues there.
//!
//! Why: a local iteration removes error on the scale of a few stitches quickly, but error that
//! is smooth across the whole grid (the tube's overall slide along the leg, its girth) takes a
//! number of iterations that grows with the grid size: as its square for plain relaxation like
//! the paper's, linearly with momentum. On a coarse grid that same smooth error is a few stitches
//! wide and cheap to remove, and each level starts from a state close to its own rest.
//!
//! It does not keep the finest grid's work flat: that level still needs more iterations the
//! finer the grid, and sending the fine residual back down (V-cycles, FAS) has not been shown to
//! help here (docs/decisions/0025).
//!
//! Coarser levels stop at [`COARSE_TOLERANCE_FACTOR`] times the tolerance. The finest level
//! converges at the tolerance, then polishes its residual towards that same tenth, best effort
//! ([`Polish`]): it often starts under the tolerance after interpolation and would otherwise stop
//! with the coarse level's slow slide over the toe still in it (docs/decisions/0067 and 0069).

use super::accelerated::{relax_accelerated, LevelStats, Polish};
use super::{Constraints, ForceTerms, RelaxObserver};
use crate::base::{GridSize, Vec3};
use crate::error::Result;
use crate::knit::Knit;

/// Coarsening stops before a grid would have fewer than this many wales or courses. Coarser
/// rings are polygons whose corners catch on the leg (a point of a 19-wale ring spans 2 cm of
/// thigh), and their contact chatters instead of settling.
pub const COARSEST: usize = 24;
/// Fewest wales or courses on the coarsest grid of a stocking to the toe: 24 courses over a
/// leg and foot of 70 cm put rings 3 cm apart, coarser than the heel, and that level chattered.
/// At 48 a 100×100 stocking gets a 50-wale level, which removes the courses' slide along the
/// leg that its finest level cannot see (decision 0061).
pub const STOCKING_COARSEST: usize = 48;
/// Iterations a coarser level may take at most: it only makes the starting point of the next,
/// so one that has not converged by then hands on what it has. At the default tolerance the
/// samples' coarse levels take 1,000–6,500.
pub const COARSE_LEVEL_ITERATIONS: usize = 10_000;
/// Coarser levels stop at this many times the tolerance asked for. The finer level cannot see
/// the smooth error a coarse level leaves (the courses' slide along the leg: its residual is
/// the course-to-course difference of wale tension, the smaller the finer the grid), so it
/// stops at the tolerance with that error still in it. Coarse iterations are cheap: at a tenth
/// of the tolerance a whole stocking's leg above the ankle is within 0.2–2.3 % in pressure of
/// its rest (3–8 % at twice it), for 1.1–1.7× the run's time (docs/decisions/0060).
///
/// The finest level polishes its residual towards the same fraction once it has met the
/// tolerance, in at most [`COARSE_LEVEL_ITERATIONS`] more iterations and never failing for it
/// ([`Polish`]): it often starts under the tolerance and would keep the coarse level's slide
/// over the toe (docs/decisions/0067 and 0069).
pub const COARSE_TOLERANCE_FACTOR: f64 = 0.1;

/// A coarser level stopped as futile hands its state on all the same when its residual is
/// below this many times its tolerance: close enough to be a start. Further off (a fit that
/// cannot hold on the leg, residuals of 1e-2 and more) it stops the fit there. Only
/// tolerances looser than 2e-2 reach past [`HAND_ON_RESIDUAL_FLOOR`] with it.
pub const HAND_ON_RESIDUAL_FACTOR: f64 = 5.0;

/// A coarser level stopped as futile below this residual hands its state on whatever the
/// tolerance asked: a coarse grid's ring corners chatter at a knee at every tolerance, and a
/// state that close to rest is still a good start.
pub const HAND_ON_RESIDUAL_FLOOR: f64 = 1e-2;

/// How the caller makes the knit and constraints of each level: the solver knows grids, the
/// caller knows what is knitted and what it touches.
pub trait Levels {
    /// The knit of a `grid`, at its starting positions (used as they are on the coarsest
    /// level; finer levels are overwritten by interpolation); `finest` for the grid the fit
    /// ends on.
    fn knit(&mut self, grid: GridSize, finest: bool) -> Knit;
    /// Fresh constraints for `knit` (per-point state belongs to one level), keeping any counters
    /// the caller reports.
    fn constraints(&mut self, knit: &Knit) -> &mut dyn Constraints;
    /// Checks a level's rest state before a finer level starts from it: the caller refuses
    /// what is no use (a fit bunched on a coarse grid stays bunched on the finer ones).
    fn accept(&mut self, _knit: &Knit) -> Result<()> {
        Ok(())
    }
    /// The grids to solve on, coarsest first, ending at `grid` (default: halving down to
    /// [`COARSEST`], [`grid_sizes_down_to`]). A stocking to the toe follows the real stitch
    /// count's own levels ([`grid_sizes_following`]).
    fn grid_sizes(&self, grid: GridSize) -> Vec<GridSize> {
        grid_sizes_down_to(grid, COARSEST)
    }
}

/// What a multilevel relaxation did, level by level.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct MultilevelStats {
    /// Coarsest level first; the last is the grid asked for.
    pub levels: Vec<LevelStats>,
}

impl MultilevelStats {
    /// The level of the grid asked for.
    pub fn fine(&self) -> &LevelStats {
        self.levels.last().expect("a multilevel solve has a level")
    }

    /// Iterations over all levels.
    pub fn total_iterations(&self) -> usize {
        self.levels.iter().map(|l| l.iterations).sum()
    }

    /// Work in iterations of the finest grid: each level's iterations weighted by its points.
    pub fn fine_grid_equivalent_iterations(&self) -> f64 {
        let fine = self.fine();
        let fine_points = (fine.wales * fine.courses) as f64;
        self.levels
            .iter()
            .map(|l| l.iterations as f64 * (l.wales * l.courses) as f64 / fine_points)
            .sum()
    }
}

/// Grid sizes from the coarsest to `grid`, each about half the next in both
/// directions, with at least `coarsest` wales and courses on every level ([`COARSEST`] for a
/// tube, [`STOCKING_COARSEST`] for a stocking to the toe). A closed course of `w` points
/// coarsens to `⌈w/2⌉`; a wale of `c` points (`c − 1` intervals between the held end rings) to
/// `⌈(c − 1)/2⌉ + 1`.
pub fn grid_sizes_down_to(grid: GridSize, coarsest: usize) -> Vec<GridSize> {
    let mut sizes = vec![grid];
    loop {
        let GridSize { wales, courses } = *sizes.last().expect("starts non-empty");
        let coarser = GridSize::new(wales.div_ceil(2), (courses - 1).div_ceil(2) + 1);
        if coarser.wales < coarsest || coarser.courses < coarsest {
            break;
        }
        sizes.push(coarser);
    }
    sizes.reverse();
    sizes
}

/// Grid sizes for a `grid` stocking that follows the real stitch count's (`real`) own path:
/// the levels of the real count's chain ([`grid_sizes_down_to`] to `coarsest`) with no more
/// wales than the grid, whatever their courses, and no smaller than `coarsest` (the real count
/// itself only where it is the grid), then the grid. So a grid with fewer courses than the
/// stitch's (an N×N one, 100×100 where the real count's chain has 100×176) is solved on the
/// chain's level with its wales first. Where there are none, the real count's coarsest level
/// if that is still the coarser grid (fewer wales, fewer points), else the grid's own chain.
/// A stocking's foot has more than one rest and settles in the one its coarse levels lead to,
/// the real count's too (decisions 0062 and 0071), so a grid follows the real count's path as
/// far as its wales allow (decisions 0063, 0066 and 0072). [`largest_level`] is what that
/// costs in points.
pub fn grid_sizes_following(real: GridSize, grid: GridSize, coarsest: usize) -> Vec<GridSize> {
    let chain = grid_sizes_down_to(real, coarsest);
    let fits = |level: &GridSize| level.wales.min(level.courses) >= coarsest;
    let mut sizes: Vec<GridSize> = chain
        .iter()
        .copied()
        .filter(|level| fits(level) && level.wales <= grid.wales && *level != real)
        .filter(|&level| level != grid)
        .collect();
    if sizes.is_empty() {
        match chain.first().copied() {
            Some(level)
                if fits(&level) && level.wales < grid.wales && level.points() < grid.points() =>
            {
                sizes.push(level)
            }
            _ => return grid_sizes_down_to(grid, coarsest),
        }
    }
    sizes.push(grid);
    sizes
}

/// The level of `sizes` with the most points: the grid itself, or where it
/// follows the real count's chain with fewer courses than the stitch's
/// ([`grid_sizes_following`]), the chain's level with its wales (about the points of the grid
/// whose courses follow the stitch: 1.75–2× an N×N grid's on the samples' stockings).
pub fn largest_level(sizes: &[GridSize]) -> GridSize {
    sizes
        .iter()
        .copied()
        .max_by_key(|level| level.points())
        .unwrap_or_default()
}

/// Relaxes a knit of `grid` coarse to fine (module docs); returns the fine knit at rest
/// and each level's figures, or, where a level stopped as futile ([`LevelStats::stall`]), that
/// level's knit and the figures so far. Coarser levels run to [`COARSE_TOLERANCE_FACTOR`] times
/// `tolerance`, in at most [`COARSE_LEVEL_ITERATIONS`]. The finest runs to `tolerance` or
/// `max_iterations`; once it meets `tolerance` it polishes its residual towards
/// [`COARSE_TOLERANCE_FACTOR`] times it, in at most [`COARSE_LEVEL_ITERATIONS`] more iterations
/// (and within `max_iterations`), and converges whatever that reaches ([`Polish`]).
///
/// Errors: those of [`relax_accelerated`], and a coarser level's state that
/// [`Levels::accept`] refuses.
pub fn relax_multilevel(
    levels: &mut dyn Levels,
    grid: GridSize,
    terms: &ForceTerms,
    tolerance: f64,
    max_iterations: usize,
    observer: &mut dyn RelaxObserver,
) -> Result<(Knit, MultilevelStats)> {
    let mut stats = MultilevelStats::default();
    let mut coarser: Option<Knit> = None;
    let sizes = levels.grid_sizes(grid);
    for (n, &level_grid) in sizes.iter().enumerate() {
        let finest = n + 1 == sizes.len();
        let mut knit = levels.knit(level_grid, finest);
        if let Some(coarse) = &coarser {
            prolong(coarse, &mut knit);
        }
        let constraints = levels.constraints(&knit);
        if coarser.is_some() {
            let p = &mut knit.particles;
            constraints.settle(&mut p.x, &p.inv_mass);
        }
        let level = relax_accelerated(
            &mut knit,
            terms,
            if finest {
                tolerance
            } else {
                tolerance * COARSE_TOLERANCE_FACTOR
            },
            if finest {
                max_iterations
            } else {
                max_iterations.min(COARSE_LEVEL_ITERATIONS)
            },
            finest.then_some(Polish {
                residual: tolerance * COARSE_TOLERANCE_FACTOR,
                max_iterations: COARSE_LEVEL_ITERATIONS,
            }),
            constraints,
            observer,
            stats.total_iterations(),
        )?;
        // A coarser level that stalled close to its tolerance still hands on a useful start
        // (a stocking's heel and toe keep a coarse grid's contact chattering there).
        let level_tolerance = if finest {
            tolerance
        } else {
            tolerance * COARSE_TOLERANCE_FACTOR
        };
        let hand_on_below = (HAND_ON_RESIDUAL_FACTOR * level_tolerance).max(HAND_ON_RESIDUAL_FLOOR);
        let stalled = level.stall.is_some() && (finest || level.residual >= hand_on_below);
        stats.levels.push(level);
        if !finest && !stalled {
            levels.accept(&knit)?;
        }
        coarser = Some(knit);
        // A level going nowhere hands nothing useful on: the finer ones would only spin longer.
        if stalled {
            break;
        }
    }
    Ok((coarser.expect("at least one level"), stats))
}

/// Sets the free points of `fine` to the bilinear interpolation of `coarse` at the same place
/// in the fabric: the same fraction of the way around (or across) the courses and along the
/// wales. Closed courses interpolate across the seam.
pub fn prolong(coarse: &Knit, fine: &mut Knit) {
    if coarse.short_rows().is_some() || fine.short_rows().is_some() {
        return prolong_along_wales(coarse, fine);
    }
    let (cw, cc) = (coarse.wales, coarse.courses);
    let (fw, fc) = (fine.wales, fine.courses);
    let closed = coarse.closed_courses && fine.closed_courses;
    // Position of a fine index on the coarse grid's axis of `n` points.
    let across = |w: usize| -> (usize, usize, f64) {
        if closed {
            let u = w as f64 * cw as f64 / fw as f64;
            let w0 = (u.floor() as usize).min(cw - 1);
            (w0, (w0 + 1) % cw, u - w0 as f64)
        } else {
            along(w, fw, cw)
        }
    };
    let x = &coarse.particles.x;
    // Along the wales by relaxed fabric where either grid is graded (index fractions are that on
    // even grids).
    let graded = coarse.is_graded() || fine.is_graded();
    let (coarse_places, fine_places) = match graded {
        true => (coarse.course_places(), fine.course_places()),
        false => (Vec::new(), Vec::new()),
    };
    for c in 0..fc {
        let (c0, c1, tc) = match graded {
            true => at_fraction(fraction_of(&fine_places, c), &coarse_places),
            false => along(c, fc, cc),
        };
        for w in 0..fw {
            let i = fine.point(w, c).index();
            if fine.particles.inv_mass[i] == 0.0 {
                continue;
            }
            let (w0, w1, tw) = across(w);
            let at = |w: usize, c: usize| x[coarse.point(w, c).index()];
            let lower: Vec3 = at(w0, c0) * (1.0 - tw) + at(w1, c0) * tw;
            let upper: Vec3 = at(w0, c1) * (1.0 - tw) + at(w1, c1) * tw;
            fine.particles.x[i] = lower * (1.0 - tc) + upper * tc;
            fine.particles.v[i] = Vec3::zeros();
        }
    }
}

/// [`prolong`] for knits with short rows, whose wales are chains of different lengths: each fine
/// point takes the place the same fraction of the way along its wale has on the coarse knit's
/// wales either side of it (interpolated around the course as [`prolong`] does).
fn prolong_along_wales(coarse: &Knit, fine: &mut Knit) {
    let (cw, fw) = (coarse.wales, fine.wales);
    let graded = coarse.is_graded() || fine.is_graded();
    let coarse_places: Vec<Vec<f64>> = match graded {
        true => (0..cw).map(|w| coarse.wale_chain_places(w)).collect(),
        false => Vec::new(),
    };
    let chains: Vec<Vec<Vec3>> = (0..cw)
        .map(|w| {
            let chain = coarse.wale_chain(w);
            chain
                .iter()
                .map(|p| coarse.particles.x[p.index()])
                .collect()
        })
        .collect();
    let on_chain = |w: usize, fraction: f64| -> Vec3 {
        let chain = &chains[w];
        let (i0, i1, t) = match graded {
            true => at_fraction(fraction, &coarse_places[w]),
            false => along_fraction(fraction, chain.len()),
        };
        chain[i0] * (1.0 - t) + chain[i1] * t
    };
    for w in 0..fw {
        let chain = fine.wale_chain(w);
        let (w0, w1, tw) = if coarse.closed_courses {
            let u = w as f64 * cw as f64 / fw as f64;
            let w0 = (u.floor() as usize).min(cw - 1);
            (w0, (w0 + 1) % cw, u - w0 as f64)
        } else {
            along(w, fw, cw)
        };
        let last = (chain.len() - 1).max(1) as f64;
        let places = match graded {
            true => fine.wale_chain_places(w),
            false => Vec::new(),
        };
        for (k, p) in chain.iter().enumerate() {
            let i = p.index();
            if fine.particles.inv_mass[i] == 0.0 {
                continue;
            }
            let fraction = match graded {
                true => fraction_of(&places, k),
                false => k as f64 / last,
            };
            fine.particles.x[i] = on_chain(w0, fraction) * (1.0 - tw) + on_chain(w1, fraction) * tw;
            fine.particles.v[i] = Vec3::zeros();
        }
    }
}

/// A fraction 0–1 of the way along `n` points as the two neighbouring points and the fraction
/// between them.
fn along_fraction(fraction: f64, n: usize) -> (usize, usize, f64) {
    if n < 2 {
        return (0, 0, 0.0);
    }
    let t = fraction * (n - 1) as f64;
    let i0 = (t.floor() as usize).min(n - 2);
    (i0, i0 + 1, t - i0 as f64)
}

/// Point `i`'s fraction of the way along a line whose points lie at `places`.
fn fraction_of(places: &[f64], i: usize) -> f64 {
    let total = places.last().copied().unwrap_or(0.0);
    match total > 0.0 {
        true => places[i] / total,
        false => 0.0,
    }
}

/// A fraction 0–1 of the way along a line whose points lie at `places` (ascending from 0) as the
/// two neighbouring points and the fraction between them.
fn at_fraction(fraction: f64, places: &[f64]) -> (usize, usize, f64) {
    let n = places.len();
    if n < 2 {
        return (0, 0, 0.0);
    }
    let at = fraction * places[n - 1];
    let i0 = places.partition_point(|&p| p <= at).clamp(1, n - 1) - 1;
    let span = places[i0 + 1] - places[i0];
    let t = match span > 0.0 {
        true => ((at - places[i0]) / span).clamp(0.0, 1.0),
        false => 0.0,
    };
    (i0, i0 + 1, t)
}

/// Index `i` of `n_fine` points spread end to end, as the two neighbouring points of `n_coarse`
/// and the fraction between them.
fn along(i: usize, n_fine: usize, n_coarse: usize) -> (usize, usize, f64) {
    if n_coarse < 2 || n_fine < 2 {
        return (0, 0, 0.0);
    }
    let t = i as f64 * (n_coarse - 1) as f64 / (n_fine - 1) as f64;
    let i0 = (t.floor() as usize).min(n_coarse - 2);
    (i0, i0 + 1, t - i0 as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::knit::{Pattern, Tile};

    fn tube(wales: usize, courses: usize) -> Knit {
        Knit::grid(
            wales,
            courses,
            true,
            &Tile::of(Pattern::Alternating),
            1.0,
            1.0,
            |w, c| {
                let t = std::f64::consts::TAU * w as f64 / wales as f64;
                Vec3::new(t.cos(), c as f64 / (courses - 1) as f64, t.sin())
            },
        )
    }

    #[test]
    fn grids_halve_down_to_the_coarsest_and_end_at_the_asked_size() {
        let pairs = |sizes: Vec<GridSize>| -> Vec<(usize, usize)> {
            sizes.iter().map(|g| (g.wales, g.courses)).collect()
        };
        let down = |w, c, coarsest| pairs(grid_sizes_down_to(GridSize::new(w, c), coarsest));
        let grid_sizes = |w, c| down(w, c, COARSEST);
        let follow = |real: [usize; 2], w, c, coarsest| {
            grid_sizes_following(real.into(), GridSize::new(w, c), coarsest)
        };
        assert_eq!(grid_sizes(150, 150), vec![(38, 39), (75, 76), (150, 150)]);
        assert_eq!(grid_sizes(40, 40), vec![(40, 40)]);
        assert_eq!(
            down(150, 150, STOCKING_COARSEST),
            vec![(75, 76), (150, 150)]
        );
        assert_eq!(
            down(100, 100, STOCKING_COARSEST),
            vec![(50, 51), (100, 100)]
        );
        // A stocking follows the real count's levels with no more wales than it, whatever
        // their courses (an N×N grid has fewer than the stitch's), or halves its own.
        let following = |w, c| follow([400, 701], w, c, STOCKING_COARSEST);
        assert_eq!(
            pairs(following(150, 150)),
            vec![(50, 89), (100, 176), (150, 150)]
        );
        assert_eq!(
            pairs(following(150, 263)),
            vec![(50, 89), (100, 176), (150, 263)]
        );
        assert_eq!(
            pairs(following(100, 100)),
            vec![(50, 89), (100, 176), (100, 100)]
        );
        assert_eq!(largest_level(&following(100, 100)), GridSize::new(100, 176));
        assert_eq!(largest_level(&following(150, 150)), GridSize::new(150, 150));
        assert_eq!(
            pairs(following(300, 300)),
            vec![(50, 89), (100, 176), (200, 351), (300, 300)]
        );
        assert_eq!(
            pairs(following(400, 701)),
            down(400, 701, STOCKING_COARSEST)
        );
        // More wales than the real count: never the real count itself first.
        assert_eq!(
            pairs(following(500, 100)),
            vec![(50, 89), (100, 176), (200, 351), (500, 100)]
        );
        assert_eq!(pairs(following(60, 60)), vec![(50, 89), (60, 60)]);
        let following = |w, c| follow([400, 805], w, c, STOCKING_COARSEST);
        assert_eq!(
            pairs(following(100, 100)),
            vec![(50, 102), (100, 202), (100, 100)]
        );
        assert_eq!(pairs(following(60, 80)), vec![(50, 102), (60, 80)]);
        // Where it has no level with fewer wales, its coarsest if that has fewer points.
        let following = |w, c| follow([400, 805], w, c, 60);
        assert_eq!(pairs(following(60, 80)), vec![(60, 80)]);
        // A real count too small to halve is no level below the coarsest.
        let following = |w, c| follow([40, 701], w, c, STOCKING_COARSEST);
        assert_eq!(pairs(following(60, 800)), vec![(60, 800)]);
        let real = grid_sizes(400, 1600);
        assert_eq!(real.first(), Some(&(25, 101)));
        assert_eq!(real.last(), Some(&(400, 1600)));
        for pair in real.windows(2) {
            assert!(pair[0].0 * 2 >= pair[1].0 && pair[0].1 * 2 > pair[1].1);
        }
    }

    #[test]
    fn prolongation_keeps_end_rings_and_interpolates_across_the_seam() {
        let coarse = tube(8, 5);
        let mut fine = tube(16, 9);
        for x in &mut fine.particles.x {
            *x = Vec3::zeros();
        }
        prolong(&coarse, &mut fine);
        // Every second fine point of every second ring lies on a coarse point.
        for c in 0..5 {
            for w in 0..8 {
                let f = fine.particles.x[fine.point(2 * w, 2 * c).index()];
                let k = coarse.particles.x[coarse.point(w, c).index()];
                assert!((f - k).norm() < 1e-12);
            }
        }
        // The last fine wale sits halfway between the last coarse wale and the first.
        let seam = fine.particles.x[fine.point(15, 0).index()];
        let mid = (coarse.particles.x[coarse.point(7, 0).index()]
            + coarse.particles.x[coarse.point(0, 0).index()])
            / 2.0;
        assert!((seam - mid).norm() < 1e-12);
        // End rings stay at their heights.
        for w in 0..16 {
            assert!(fine.particles.x[fine.point(w, 0).index()].y.abs() < 1e-12);
            assert!((fine.particles.x[fine.point(w, 8).index()].y - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn a_graded_grid_takes_the_coarse_fabric_at_the_same_relaxed_place() {
        // Coarse rings evenly up the fabric (height = relaxed fraction); the fine grid's
        // courses crowd towards its end: each fine ring lands at its own relaxed fraction, not
        // its index's.
        let coarse = tube(8, 5);
        let intervals = [0.3, 0.3, 0.2, 0.1, 0.05, 0.05];
        let mut fine = tube(8, 7).with_course_intervals(&intervals);
        assert!(fine.is_graded() && !coarse.is_graded());
        prolong(&coarse, &mut fine);
        let places = fine.course_places();
        for c in 0..7 {
            let y = fine.particles.x[fine.point(3, c).index()].y;
            assert!((y - places[c] / places[6]).abs() < 1e-12, "{c}: {y}");
        }
        // And back: the coarse grid's rings from the graded one's.
        let mut back = tube(8, 5);
        prolong(&fine, &mut back);
        for c in 0..5 {
            let y = back.particles.x[back.point(3, c).index()].y;
            assert!((y - c as f64 / 4.0).abs() < 1e-12, "{c}: {y}");
        }
    }
}
