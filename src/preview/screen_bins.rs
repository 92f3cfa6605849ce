//! Screen-space bins for the preview's camera rays: every leg triangle and yarn capsule listed
//! in the pixels its projection can cover, nearest first, so a sample tests only what can lie
//! on its ray.
//!
//! Method. The binning stage of a tiled rasteriser (Laine & Karras, "High-Performance Software
//! Rasterization on GPUs", HPG 2011), used for ray casting: every camera ray leaves one eye
//! point, so a primitive can meet the ray of a sample only where its projection covers that
//! sample. Each primitive's box in the camera's frame (right, up, forward) bounds its
//! projection: `x/z` over a box in front of the eye is extreme at the box's corners. The box is
//! widened by [`MARGIN_PX`], far above rounding, so the lists are conservative: a ray-cast over
//! a pixel's list finds exactly what a cast over every primitive would. Each entry keeps the
//! part of the pixel it covers in 1/256ths ([`SubPixel`]) and its depth range, so a sample
//! skips the entries beside it or beyond its search without loading the primitive.
//!
//! Built by counting sort over the pixels (counts, offsets, scatter), and each pixel's list is
//! sorted by (near depth, index): the lists are the same whatever the thread count. A primitive
//! that reaches behind the eye, or whose box covers more than [`MAX_PIXELS_PER_ITEM`] pixels,
//! is not binned but returned as *global*, for the caller to test by another structure.

use std::sync::atomic::{AtomicU64, Ordering};

use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

use super::camera::Camera;

/// How far every projected box is widened, pixels: far above the rounding of a projection
/// (10⁻¹¹ pixels at 8192 wide), far below the sub-pixel step (1/256).
pub const MARGIN_PX: f64 = 1e-3;

/// Most pixels one binned primitive may cover (its projected box, 64 × 64 at 768²): beyond, it
/// is global. A leg's triangle covers a few pixels, a yarn capsule one or two.
pub const MAX_PIXELS_PER_ITEM: f64 = 4096.0;

/// Relative widening of the depth range stored in `f32`, far above its rounding (6·10⁻⁸).
const DEPTH_SLACK: f64 = 1e-6;

/// A camera and picture size: where a point of the camera's frame lands in pixels.
#[derive(Clone, Copy, Debug)]
pub struct ScreenView<'a> {
    /// The camera.
    pub camera: &'a Camera,
    /// Picture width, pixels.
    pub width: u32,
    /// Picture height, pixels.
    pub height: u32,
}

impl ScreenView<'_> {
    /// The point `p_world` in the camera's frame: (right, up, forward), metres.
    pub fn camera_from_world(&self, p_world: &Point3<f64>) -> Vector3<f64> {
        let c = self.camera;
        let d = p_world - c.eye;
        Vector3::new(d.dot(&c.right), d.dot(&c.up), d.dot(&c.forward))
    }

    /// The camera-frame box of `points` widened by `pad` metres on every side (a capsule's
    /// radius; 0 for a triangle): it holds every point within `pad` of their hull.
    pub fn camera_box(&self, points: &[Point3<f64>], pad: f64) -> CameraBox {
        let mut lo = Vector3::repeat(f64::INFINITY);
        let mut hi = Vector3::repeat(f64::NEG_INFINITY);
        for p in points {
            let q = self.camera_from_world(p);
            lo = lo.inf(&q);
            hi = hi.sup(&q);
        }
        CameraBox {
            lo: lo.add_scalar(-pad),
            hi: hi.add_scalar(pad),
        }
    }

    /// Where a camera-frame box lands.
    fn place(&self, b: &CameraBox) -> Placement {
        let all = b.lo.iter().chain(b.hi.iter());
        if all.clone().any(|c| c.is_nan()) {
            return Placement::Global;
        }
        if b.hi.z < 0.0 {
            // Wholly behind the eye: every camera ray goes forwards.
            return Placement::Off;
        }
        if b.lo.z <= 0.0 {
            return Placement::Global;
        }
        let c = self.camera;
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        let sx = w / (2.0 * c.tan_half_fov * c.aspect);
        let sy = h / (2.0 * c.tan_half_fov);
        let (inv_near, inv_far) = (1.0 / b.lo.z, 1.0 / b.hi.z);
        // x/z over the box is extreme at its corners; z > 0 throughout.
        let ratio = |lo: f64, hi: f64| {
            let r = [lo * inv_near, lo * inv_far, hi * inv_near, hi * inv_far];
            (
                r.iter().copied().fold(f64::INFINITY, f64::min),
                r.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            )
        };
        let (rx_lo, rx_hi) = ratio(b.lo.x, b.hi.x);
        let (ry_lo, ry_hi) = ratio(b.lo.y, b.hi.y);
        // Pixel coordinates as the camera maps them (`Camera::direction`): x right, y down.
        let x_lo = w / 2.0 + rx_lo * sx - MARGIN_PX;
        let x_hi = w / 2.0 + rx_hi * sx + MARGIN_PX;
        let y_lo = h / 2.0 - ry_hi * sy - MARGIN_PX;
        let y_hi = h / 2.0 - ry_lo * sy + MARGIN_PX;
        if [x_lo, x_hi, y_lo, y_hi].iter().any(|v| v.is_nan()) {
            return Placement::Global;
        }
        if x_hi < 0.0 || y_hi < 0.0 || x_lo >= w || y_lo >= h {
            return Placement::Off;
        }
        // Casts truncate: `floor` for these non-negative values (and no call to libm's).
        let (px0, px1) = (x_lo.max(0.0) as u32, x_hi.min(w - 1.0) as u32);
        let (py0, py1) = (y_lo.max(0.0) as u32, y_hi.min(h - 1.0) as u32);
        let pixels = f64::from(px1 - px0 + 1) * f64::from(py1 - py0 + 1);
        if pixels > MAX_PIXELS_PER_ITEM {
            return Placement::Global;
        }
        Placement::Pixels {
            x: [px0, px1],
            y: [py0, py1],
            box_px: [x_lo, x_hi, y_lo, y_hi],
            depth: [
                (b.lo.z * (1.0 - DEPTH_SLACK)) as f32,
                (b.hi.z * (1.0 + DEPTH_SLACK)) as f32,
            ],
        }
    }
}

/// A box in the camera's frame (right, up, forward), metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraBox {
    /// Least corner.
    pub lo: Vector3<f64>,
    /// Greatest corner.
    pub hi: Vector3<f64>,
}

enum Placement {
    /// No camera ray can meet it.
    Off,
    /// To be tested by every ray.
    Global,
    /// Binned in the pixels `x[0]..=x[1]` × `y[0]..=y[1]`.
    Pixels {
        x: [u32; 2],
        y: [u32; 2],
        /// The widened projected box, pixels: x from, x to, y from, y to.
        box_px: [f64; 4],
        /// Forward depth range, metres, widened.
        depth: [f32; 2],
    },
}

/// A sample's place in its pixel, in 1/256ths of the pixel along x and y.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SubPixel {
    x: u8,
    y: u8,
}

impl SubPixel {
    /// The sub-pixel of the offset (`ox`, `oy`), each in [0, 1), within its pixel.
    pub fn new(ox: f64, oy: f64) -> SubPixel {
        let q = |o: f64| (o * 256.0).clamp(0.0, 255.0) as u8;
        SubPixel { x: q(ox), y: q(oy) }
    }
}

/// One primitive in one pixel's list.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Entry {
    /// The primitive's index.
    pub item: u32,
    /// Least forward depth (distance along the camera's forward axis) of any of its points,
    /// metres, rounded down.
    pub near: f32,
    /// Greatest forward depth, metres, rounded up.
    pub far: f32,
    /// The part of the pixel its projection may cover, in 1/256ths: x from, x to, y from, y to
    /// (inclusive).
    sub: [u8; 4],
}

impl Entry {
    fn of(item: u32) -> Entry {
        Entry {
            item,
            near: 0.0,
            far: 0.0,
            sub: [0; 4],
        }
    }

    /// Whether the primitive's projection may cover the sample at `s`.
    #[inline]
    pub fn covers(&self, s: SubPixel) -> bool {
        let [x0, x1, y0, y1] = self.sub;
        (x0..=x1).contains(&s.x) && (y0..=y1).contains(&s.y)
    }
}

/// Per pixel, the primitives whose projection may cover it, nearest first.
pub struct ScreenBins {
    width: u32,
    /// Start of each pixel's list in `entries` (row-major), and the end of the last.
    start: Vec<u32>,
    entries: Vec<Entry>,
}

/// The binned primitives, and those every ray must test.
pub struct Binning {
    /// The per-pixel lists.
    pub bins: ScreenBins,
    /// Primitives reaching behind the eye or too large to bin, ascending.
    pub global: Vec<u32>,
}

impl ScreenBins {
    /// Bins the `count` primitives whose camera-frame boxes `footprint` gives (`None`: a
    /// primitive no ray may meet, such as one with a non-finite point). `None` when the lists
    /// would hold more than [`PAIRS_PER_ITEM`] entries a primitive and [`PAIRS_PER_PIXEL`] a
    /// pixel, or 2³² entries.
    pub fn build<F>(view: &ScreenView, count: usize, footprint: F) -> Option<Binning>
    where
        F: Fn(usize) -> Option<CameraBox> + Sync,
    {
        let (w, h) = (view.width as usize, view.height as usize);
        // Every (pixel, entry) pair, chunk by chunk in primitive order; a global primitive as
        // one pair at `GLOBAL`.
        // The pairs made so far, against the budget: checked every `CHUNK` / 16 primitives.
        let budget = (PAIRS_PER_ITEM * count as u64).max(PAIRS_PER_PIXEL * (w * h) as u64);
        let made = AtomicU64::new(0);
        let chunks: Option<Vec<Vec<(u32, Entry)>>> = (0..count.div_ceil(CHUNK))
            .into_par_iter()
            .map(|chunk| {
                let items = chunk * CHUNK..((chunk + 1) * CHUNK).min(count);
                let mut pairs = Vec::with_capacity(items.len() * 2);
                let mut reported = 0;
                for i in items {
                    if i % (CHUNK / 16) == 0 {
                        let new = (pairs.len() - reported) as u64;
                        reported = pairs.len();
                        if made.fetch_add(new, Ordering::Relaxed) + new > budget {
                            return None;
                        }
                    }
                    let item = i as u32;
                    match footprint(i).map_or(Placement::Off, |b| view.place(&b)) {
                        Placement::Off => {}
                        Placement::Global => pairs.push((GLOBAL, Entry::of(item))),
                        Placement::Pixels {
                            x,
                            y,
                            box_px,
                            depth,
                        } => {
                            for py in y[0]..=y[1] {
                                let fy = f64::from(py);
                                let sub_y = [sub_step(box_px[2] - fy), sub_step(box_px[3] - fy)];
                                for px in x[0]..=x[1] {
                                    let fx = f64::from(px);
                                    let entry = Entry {
                                        item,
                                        near: depth[0],
                                        far: depth[1],
                                        sub: [
                                            sub_step(box_px[0] - fx),
                                            sub_step(box_px[1] - fx),
                                            sub_y[0],
                                            sub_y[1],
                                        ],
                                    };
                                    pairs.push((py * view.width + px, entry));
                                }
                            }
                        }
                    }
                }
                Some(pairs)
            })
            .collect();
        let chunks = chunks?;
        let mut start = vec![0u32; w * h + 1];
        let mut global = Vec::new();
        for (pixel, entry) in chunks.iter().flatten() {
            match *pixel {
                GLOBAL => global.push(entry.item),
                p => start[p as usize + 1] += 1,
            }
        }
        let mut total = 0u64;
        for s in &mut start {
            total += u64::from(*s);
            if total >= u64::from(u32::MAX) {
                return None;
            }
            *s = total as u32;
        }
        let mut entries = vec![Entry::of(0); total as usize];
        let mut cursor: Vec<u32> = start[..w * h].to_vec();
        // Each chunk is freed once scattered.
        for chunk in chunks {
            for (pixel, entry) in chunk {
                if pixel != GLOBAL {
                    let at = &mut cursor[pixel as usize];
                    entries[*at as usize] = entry;
                    *at += 1;
                }
            }
        }
        drop(cursor);
        // Nearest first; the index breaks ties, so the order is total.
        let mut rows: Vec<(usize, &mut [Entry])> = Vec::with_capacity(h);
        let mut rest = entries.as_mut_slice();
        for y in 0..h {
            let len = (start[(y + 1) * w] - start[y * w]) as usize;
            let (row, tail) = rest.split_at_mut(len);
            rows.push((y, row));
            rest = tail;
        }
        rows.into_par_iter().for_each(|(y, row)| {
            let base = start[y * w];
            for x in 0..w {
                let (a, b) = (start[y * w + x] - base, start[y * w + x + 1] - base);
                // `near` is positive, so its bits order as its value.
                row[a as usize..b as usize].sort_unstable_by_key(|e| {
                    u64::from(e.near.to_bits()) << 32 | u64::from(e.item)
                });
            }
        });
        Some(Binning {
            bins: ScreenBins {
                width: view.width,
                start,
                entries,
            },
            global,
        })
    }

    /// The list of pixel (`x`, `y`), nearest first.
    #[inline]
    pub fn pixel(&self, x: u32, y: u32) -> &[Entry] {
        let p = y as usize * self.width as usize + x as usize;
        &self.entries[self.start[p] as usize..self.start[p + 1] as usize]
    }

    /// Number of (pixel, primitive) entries.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True when no primitive is binned.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

/// The 1/256th of the pixel in which a box's edge `at` pixels into the pixel lies: its first
/// or last covered step (the cast truncates, as `floor` for what the clamp leaves).
fn sub_step(at: f64) -> u8 {
    (at * 256.0).clamp(0.0, 255.0) as u8
}

/// Most (pixel, primitive) pairs a binning may make, per primitive or per pixel, whichever
/// allows more: a leg's triangles make a few per pixel they cover, a fit's capsules one or two
/// each. Beyond (a damaged file's long segments), binning stops and the caller falls back to
/// its whole-scene structure, whose memory is bounded by its own rules.
pub const PAIRS_PER_ITEM: u64 = 64;
/// See [`PAIRS_PER_ITEM`].
pub const PAIRS_PER_PIXEL: u64 = 8;

/// Primitives binned by one task: enough to amortise a task, few enough to balance two cores.
const CHUNK: usize = 1 << 14;

/// The pixel key of a global primitive's pair.
const GLOBAL: u32 = u32::MAX;

#[cfg(test)]
mod tests {
    use super::*;

    fn view(camera: &Camera) -> ScreenView<'_> {
        ScreenView {
            camera,
            width: 40,
            height: 30,
        }
    }

    #[test]
    fn a_point_lands_in_the_pixel_whose_ray_passes_through_it() {
        let camera = Camera::look_at(
            Point3::new(0.1, 0.2, 2.0),
            Point3::new(0.0, 0.0, 0.0),
            30.0,
            4.0 / 3.0,
        );
        let v = view(&camera);
        for (u, t) in [(0.13, 0.71), (0.5, 0.5), (0.97, 0.02), (0.0, 0.999)] {
            let p = camera.eye + camera.direction(u, t) * 1.7;
            let b = v.camera_box(&[p], 0.0);
            let Placement::Pixels { x, y, box_px, .. } = v.place(&b) else {
                panic!("not binned");
            };
            let (px, py) = (u * 40.0, t * 30.0);
            assert!(x[0] as f64 <= px && px < x[1] as f64 + 1.0, "{u}: {x:?}");
            assert!(y[0] as f64 <= py && py < y[1] as f64 + 1.0, "{t}: {y:?}");
            assert!(box_px[0] <= px && px <= box_px[1] && box_px[1] - box_px[0] < 0.01);
            assert!(box_px[2] <= py && py <= box_px[3] && box_px[3] - box_px[2] < 0.01);
        }
    }

    #[test]
    fn what_reaches_behind_the_eye_is_global_and_what_is_behind_is_off() {
        let camera = Camera::look_at(Point3::new(0.0, 0.0, 1.0), Point3::origin(), 30.0, 1.0);
        let v = view(&camera);
        let straddling = v.camera_box(
            &[Point3::new(0.0, 0.0, 0.5), Point3::new(0.0, 0.0, 1.5)],
            0.0,
        );
        assert!(matches!(v.place(&straddling), Placement::Global));
        let behind = v.camera_box(&[Point3::new(0.0, 0.0, 1.5)], 0.1);
        assert!(matches!(v.place(&behind), Placement::Off));
        let beside = v.camera_box(&[Point3::new(5.0, 0.0, 0.0)], 0.1);
        assert!(matches!(v.place(&beside), Placement::Off));
        let huge = v.camera_box(
            &[Point3::new(-1.0, -1.0, 0.0), Point3::new(1.0, 1.0, 0.0)],
            0.0,
        );
        assert!(matches!(v.place(&huge), Placement::Pixels { .. }));
    }

    #[test]
    fn binning_stops_at_its_budget_of_entries() {
        let camera = Camera::look_at(Point3::new(0.0, 0.0, 1.0), Point3::origin(), 30.0, 1.0);
        let v = view(&camera);
        // Each box covers most of the 40 × 30 picture: 2,000 of them are a million entries.
        let wide = v.camera_box(
            &[Point3::new(-0.2, -0.2, 0.0), Point3::new(0.2, 0.2, 0.0)],
            0.0,
        );
        assert!(ScreenBins::build(&v, 2000, |_| Some(wide)).is_none());
        assert!(ScreenBins::build(&v, 20, |_| Some(wide)).is_some());
    }

    #[test]
    fn lists_are_nearest_first_and_the_same_on_one_thread() {
        let camera = Camera::look_at(Point3::new(0.0, 0.0, 1.0), Point3::origin(), 30.0, 1.0);
        let v = view(&camera);
        let points: Vec<Point3<f64>> = (0..500)
            .map(|i| {
                let f = i as f64;
                Point3::new(
                    (f * 0.37).sin() * 0.2,
                    (f * 0.71).cos() * 0.2,
                    (f * 0.13).sin() * 0.1,
                )
            })
            .collect();
        let footprint = |i: usize| Some(v.camera_box(&points[i..=i], 0.01));
        let many = ScreenBins::build(&v, points.len(), footprint).unwrap();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| ScreenBins::build(&v, points.len(), footprint).unwrap());
        assert_eq!(many.bins.entries, one.bins.entries);
        assert_eq!(many.bins.start, one.bins.start);
        assert!(many.global.is_empty() && !many.bins.is_empty());
        for y in 0..30 {
            for x in 0..40 {
                let list = many.bins.pixel(x, y);
                assert!(list.windows(2).all(|p| p[0].near <= p[1].near));
            }
        }
    }
}
