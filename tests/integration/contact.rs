//! Sliding contact (`sim::contact::LegContact`, paper §6.2) on a thin rod: moves of any length
//! and aim never end inside it, the exact pass after a fit leaves every point at the offset,
//! and a point that rises off its cached tangent plane stops being held. The properties over
//! random moves and every sample leg are in `properties.rs`.

use knitfit::base::Vec3;
use knitfit::leg::{Collider, ContactMethod, Leg};
use knitfit::sim::contact::LegContact;
use knitfit::sim::Constraints;
use nalgebra::Point3;

use crate::support::revolved;

/// A capped rod of radius `r` along Y, 0.1 m long, counter-clockwise outside.
fn rod(r: f64) -> Leg {
    revolved("rod", 24, 10, (0.0, 0.1), |_| r)
}

/// A seeded generator of numbers in [-1, 1) (no entropy: tests are reproducible).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

#[test]
fn no_move_ends_inside_a_thin_rod_however_it_is_aimed() {
    let radius = 0.003;
    let offset = 0.00003;
    let leg = rod(radius);
    for method in [ContactMethod::Bvh, ContactMethod::Brute] {
        let collider = Collider::new(&leg, method).unwrap();
        let n = 200;
        let mut rng = Lcg(7);
        // Points start just outside the rod (0.1 mm off the skin) at random places.
        let mut x: Vec<Vec3> = (0..n)
            .map(|_| {
                let t = std::f64::consts::PI * rng.next();
                let y = 0.05 + 0.03 * rng.next();
                Vec3::new((radius + 1e-4) * t.cos(), y, (radius + 1e-4) * t.sin())
            })
            .collect();
        let mut contact = LegContact::new(&collider, offset, 0.01, Vec3::y(), vec![false; n]);
        let inv_mass = vec![1.0; n];
        for step in 0..40 {
            let from = x.clone();
            // Moves up to 8 mm long in any direction (many go straight through the rod),
            // then short ones that slide on cached tangent planes.
            let length = if step < 20 { 0.008 } else { 0.0003 };
            for p in x.iter_mut() {
                *p += Vec3::new(rng.next(), 0.3 * rng.next(), rng.next()) * length;
            }
            contact.constrain(&from, &mut x, &inv_mass);
            for p in &x {
                let d = collider.closest(&Point3::from(*p)).signed_distance;
                assert!(
                    d >= offset * 0.999,
                    "{method:?}: a point ended {d} m from the skin"
                );
            }
        }
        assert!(contact.counters().slides > 0, "the moves did hit the rod");
    }
}

#[test]
fn the_exact_pass_moves_every_point_out_to_the_offset_and_leaves_held_ones() {
    let (radius, offset) = (0.003, 0.00003);
    let leg = rod(radius);
    let collider = Collider::new(&leg, ContactMethod::Bvh).unwrap();
    let mut rng = Lcg(11);
    // Points from 1 mm inside to 1 mm outside the rod; the last few belong to a locked ring
    // (held at y = 0.05, may only move within that plane), and one is held outright.
    let n = 100;
    let mut x: Vec<Vec3> = (0..n)
        .map(|i| {
            let t = std::f64::consts::PI * rng.next();
            let r = radius + 0.001 * rng.next();
            let y = if i >= 90 {
                0.05
            } else {
                0.05 + 0.03 * rng.next()
            };
            Vec3::new(r * t.cos(), y, r * t.sin())
        })
        .collect();
    let mut inv_mass = vec![1.0; n];
    inv_mass[0] = 0.0;
    let held = x[0];
    let locked: Vec<bool> = (0..n).map(|i| i >= 90).collect();
    let mut contact = LegContact::new(&collider, offset, 0.01, Vec3::y(), locked);
    contact.finish(&mut x, &inv_mass);
    assert_eq!(x[0], held);
    for (i, p) in x.iter().enumerate().skip(1) {
        let d = collider.closest(&Point3::from(*p)).signed_distance;
        assert!(d >= offset * 0.999, "point {i} ended {d} m from the skin");
        if i >= 90 {
            assert_eq!(p.y, 0.05, "a locked point stays in its ring's plane");
        }
    }
    assert!(contact.counters().finished_out > 10);
}

#[test]
fn a_point_that_rises_off_its_plane_is_no_longer_held() {
    let radius = 0.01;
    let offset = 0.00003;
    let leg = rod(radius);
    let collider = Collider::new(&leg, ContactMethod::Bvh).unwrap();
    // On the rod's flat face at +X (its first facet's middle), pressed straight in.
    let t = std::f64::consts::TAU / 48.0;
    let face = Vec3::new(t.cos(), 0.0, -t.sin());
    let on_skin = face * (radius * (std::f64::consts::PI / 24.0).cos()) + Vec3::y() * 0.05;
    let mut contact = LegContact::new(&collider, offset, 0.01, Vec3::y(), vec![false]);
    let mut x = [on_skin - face * 0.001];
    contact.settle(&mut x, &[1.0]);
    // A first move that slides, so the point touches a cached plane.
    let mut from = x;
    x[0] += face * -0.00001 + Vec3::y() * 0.00001;
    contact.constrain(&from, &mut x, &[1.0]);
    let pressing = face * -1.0;
    assert!(
        contact.unheld_force(0, &pressing).norm() < 1e-9,
        "resting: held"
    );
    // Rise in steps far shorter than the plane's reuse distance.
    let mut held_at = Vec::new();
    for _ in 0..10 {
        from = x;
        x[0] += face * (0.1 * offset);
        contact.constrain(&from, &mut x, &[1.0]);
        held_at.push(contact.unheld_force(0, &pressing).norm() < 1e-9);
    }
    // Held up to half the offset above the plane (what an exact query calls touching),
    // then the force that presses it back acts on it.
    assert_eq!(&held_at[..4], &[true; 4]);
    assert_eq!(&held_at[5..], &[false; 5]);
}
