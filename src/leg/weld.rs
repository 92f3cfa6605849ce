//! Vertex welding by exact position: exporters often write a vertex once per triangle (flat
//! shading, hard edges, UV seams), so vertex indices alone do not say which triangles touch.
//! Cleaning ([`super::clean`]) merges them with these ids, so every later question about the
//! leg (open edges, winding, cross-sections) sees triangles that share what they touch.

use std::collections::HashMap;

use nalgebra::Point3;

/// Per vertex, the index of the first vertex at exactly the same position (itself when it is
/// the first). Positions are compared bit for bit, with −0 taken as +0.
pub fn welded_ids(positions: &[Point3<f64>]) -> Vec<u32> {
    let mut first: HashMap<[u64; 3], u32> = HashMap::with_capacity(positions.len());
    positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let key = [p.x, p.y, p.z].map(|c| (c + 0.0).to_bits());
            *first.entry(key).or_insert(i as u32)
        })
        .collect()
}

/// A triangle's vertices as welded ids, or `None` when two of them weld together (the
/// triangle has no area and joins nothing).
pub fn welded_triangle(welded: &[u32], t: &[u32; 3]) -> Option<[u32; 3]> {
    let w = t.map(|i| welded[i as usize]);
    (w[0] != w[1] && w[1] != w[2] && w[2] != w[0]).then_some(w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_positions_share_the_first_id_and_slivers_are_dropped() {
        let p = |x: f64| Point3::new(x, 0.0, 0.0);
        let welded = welded_ids(&[p(0.0), p(1.0), p(-0.0), p(1.0), p(2.0)]);
        assert_eq!(welded, [0, 1, 0, 1, 4]);
        assert_eq!(welded_triangle(&welded, &[0, 1, 4]), Some([0, 1, 4]));
        assert_eq!(welded_triangle(&welded, &[0, 2, 4]), None);
    }
}
