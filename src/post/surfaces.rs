//! The fitted knit and the leg as the triangle surfaces the writers and the preview take: the
//! leg with its per-vertex fields and a density heat map, and the stocking as a surface whose
//! texture coordinates run along the knit (u around, v along) without a jump at the seam.

use std::collections::BTreeMap;

use super::fields::KnitFields;
use crate::base::{colour, SurfaceMesh, YarnGeometry};
use crate::knit::Knit;
use crate::leg::Leg;

/// The leg with its fields as attributes (`stitch_density`, `stretch_course`, `stretch_wale`,
/// `coverage`) and the density's heat map as vertex colours.
pub fn leg_surface(leg: &Leg, fields: &KnitFields) -> SurfaceMesh {
    let positions = leg.positions.iter().map(|p| p.coords.into()).collect();
    let mut mesh = SurfaceMesh::new("leg", positions, leg.triangles.clone());
    let density = &fields.stitch_density;
    if density.len() != leg.positions.len() {
        // No attributes asked for.
        return mesh;
    }
    let covered = density.iter().copied().filter(|&d| d > 0.0);
    let (lo, hi) = covered.fold((f64::INFINITY, 0.0f64), |(lo, hi), d| {
        (lo.min(d), hi.max(d))
    });
    let uncovered = [0.2f32, 0.2, 0.2];
    mesh.colours = Some(
        density
            .iter()
            .map(|&d| {
                if d > 0.0 {
                    colour::heat(if hi > lo { (d - lo) / (hi - lo) } else { 0.5 })
                } else {
                    uncovered
                }
            })
            .collect(),
    );
    for (name, values) in fields.named() {
        mesh.point_attributes
            .insert(name.into(), values.iter().map(|&v| v as f32).collect());
    }
    mesh
}

/// The fitted knit as a triangle surface: the grid triangulated with the seam column repeated
/// so texture coordinates (wale, course) run 0–1 without a jump; per vertex, the yarn point's
/// attributes and its fields (density, stretch, coverage: what a sheer shader on this surface
/// needs). Only the knit's own points are used: `yarns` may hold points the penetration fix
/// inserted after them.
pub fn stocking_surface(
    knit: &Knit,
    knit_fields: &KnitFields,
    yarns: &YarnGeometry,
) -> SurfaceMesh {
    let (wales, courses) = (knit.wales, knit.courses);
    let columns = wales + 1;
    let source = |w: usize, c: usize| knit.point(w % wales, c).index();
    let mut positions = Vec::with_capacity(columns * courses);
    let mut texcoords = Vec::with_capacity(columns * courses);
    let point_fields: Vec<(&str, &[f32])> = yarns
        .point_attributes
        .iter()
        .map(|(k, v)| (k.as_str(), &v[..knit.len()]))
        .collect();
    let knit_fields: Vec<(&str, Vec<f32>)> = knit_fields
        .named()
        .into_iter()
        .filter(|(_, v)| v.len() == knit.len())
        .map(|(k, v)| (k, v.iter().map(|&x| x as f32).collect()))
        .collect();
    let sources: Vec<(&str, &[f32])> = point_fields
        .into_iter()
        .chain(knit_fields.iter().map(|(k, v)| (*k, &v[..])))
        .collect();
    let mut attributes: BTreeMap<String, Vec<f32>> = sources
        .iter()
        .map(|(k, _)| (k.to_string(), Vec::new()))
        .collect();
    for c in 0..courses {
        for w in 0..columns {
            let i = source(w, c);
            let p = knit.particles.x[i];
            positions.push([p.x, p.y, p.z]);
            texcoords.push([
                w as f32 / wales as f32,
                1.0 - c as f32 / (courses - 1).max(1) as f32,
            ]);
            for (name, values) in &sources {
                attributes
                    .get_mut(*name)
                    .expect("made above")
                    .push(values[i]);
            }
        }
    }
    let id = |w: usize, c: usize| (c * columns + w) as u32;
    let mut triangles = Vec::with_capacity(2 * wales * courses);
    for c in 0..courses.saturating_sub(1) {
        for w in 0..wales {
            // Counter-clockwise seen from outside: around the axis, then up it.
            triangles.push([id(w, c), id(w + 1, c), id(w + 1, c + 1)]);
            triangles.push([id(w, c), id(w + 1, c + 1), id(w, c + 1)]);
        }
    }
    let mut mesh = SurfaceMesh::new("stocking", positions, triangles);
    // The repeated seam column must share the normal of the column it repeats.
    for c in 0..courses {
        let (first, last) = (id(0, c) as usize, id(wales, c) as usize);
        let n = nalgebra::Vector3::from(mesh.normals[first])
            + nalgebra::Vector3::from(mesh.normals[last]);
        let n = if n.norm() > 0.0 {
            n.normalize()
        } else {
            nalgebra::Vector3::y()
        };
        mesh.normals[first] = n.into();
        mesh.normals[last] = n.into();
    }
    mesh.texcoords = Some(texcoords);
    mesh.point_attributes = attributes;
    mesh
}
