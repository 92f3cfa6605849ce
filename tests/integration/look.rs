//! How `stocking.glb` looks opened as it is: the leg in skin (or its file's own material) with
//! no heat map a viewer would paint over it, and the sheer stocking surface clear of the skin, so
//! no depth buffer or ray tracer mixes the two up. The renders in the clients themselves
//! (three.js, Blender) are `tools/client_check.sh`, run by `.ci/run`.

use std::path::{Path, PathBuf};

use knitfit::base::Material;
use knitfit::post::surfaces::STOCKING_CLEARANCE_M;
use nalgebra::Point3;

use crate::skin::collider_of;
use crate::support::{edited_sample, fit, knitfit, procedural_leg, stderr, FEET};

fn sample(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("samples")
        .join(name)
}

/// The glTF document of a fit's `stocking.glb`, and its buffers.
fn stocking_glb(out: &Path) -> (gltf::Document, Vec<gltf::buffer::Data>) {
    let (doc, buffers, _) = gltf::import(out.join("stocking.glb")).unwrap();
    (doc, buffers)
}

/// The first primitive of the node named `name`.
fn primitive<'a>(doc: &'a gltf::Document, name: &str) -> gltf::Primitive<'a> {
    doc.nodes()
        .find(|n| n.name() == Some(name))
        .and_then(|n| n.mesh())
        .and_then(|m| m.primitives().next())
        .unwrap_or_else(|| panic!("no mesh node {name:?}"))
}

#[test]
fn the_leg_is_drawn_in_skin_without_a_heat_map_and_the_stocking_sheer_over_it() {
    let (dir, _) = fit(&procedural_leg(), "40x40", &[]);
    let (doc, _) = stocking_glb(&dir.path().join("out"));
    let leg = primitive(&doc, "leg");
    // glTF multiplies COLOR_0 into the base colour: a heat map there replaces the skin.
    assert!(
        leg.get(&gltf::Semantic::Colors(0)).is_none(),
        "the leg has COLOR_0"
    );
    assert!(
        leg.get(&gltf::Semantic::Extras("STITCH_DENSITY".into()))
            .is_some(),
        "the leg keeps its fields"
    );
    let skin = Material::skin();
    let material = leg.material();
    assert_eq!(material.name(), Some(skin.name.as_str()));
    assert_eq!(material.alpha_mode(), gltf::material::AlphaMode::Opaque);
    let pbr = material.pbr_metallic_roughness();
    for (got, want) in pbr.base_color_factor().iter().zip(skin.base_colour) {
        assert!((f64::from(*got) - want).abs() < 1e-6, "{got} vs {want}");
    }
    let stocking = primitive(&doc, "stocking");
    assert_eq!(
        stocking.material().alpha_mode(),
        gltf::material::AlphaMode::Blend
    );
    assert!(stocking.get(&gltf::Semantic::Colors(0)).is_some());
}

#[test]
fn a_legs_own_material_is_carried_over_unless_it_is_textured() {
    let dir = tempfile::tempdir().unwrap();
    let with_material = |textured: bool| {
        move |root: &mut gltf_json::Root| {
            let mut pbr = gltf_json::material::PbrMetallicRoughness {
                base_color_factor: gltf_json::material::PbrBaseColorFactor([0.5, 0.3, 0.2, 1.0]),
                roughness_factor: gltf_json::material::StrengthFactor(0.7),
                ..Default::default()
            };
            if textured {
                // A texture that the leg, written without texture coordinates, cannot carry.
                pbr.base_color_texture = Some(gltf_json::texture::Info {
                    index: gltf_json::Index::new(0),
                    tex_coord: 0,
                    extensions: None,
                    extras: Default::default(),
                });
                root.images.push(gltf_json::Image {
                    buffer_view: None,
                    mime_type: None,
                    name: None,
                    uri: Some("skin.png".into()),
                    extensions: None,
                    extras: Default::default(),
                });
                root.textures.push(gltf_json::Texture {
                    name: None,
                    sampler: None,
                    source: gltf_json::Index::new(0),
                    extensions: None,
                    extras: Default::default(),
                });
            }
            root.materials.push(gltf_json::Material {
                name: Some("character_skin".into()),
                pbr_metallic_roughness: pbr,
                ..Default::default()
            });
            for mesh in &mut root.meshes {
                for p in &mut mesh.primitives {
                    p.material = Some(gltf_json::Index::new(0));
                }
            }
        }
    };
    for (textured, want) in [(false, "character_skin"), (true, "skin")] {
        let leg = edited_sample(
            dir.path(),
            &format!("leg_{textured}.glb"),
            with_material(textured),
        );
        let out = dir.path().join(format!("out_{textured}"));
        let run = knitfit(
            dir.path(),
            &[
                "fit",
                "--leg",
                leg.to_str().unwrap(),
                "--resolution",
                "24x24",
                "--out",
                out.to_str().unwrap(),
                "-q",
            ],
        );
        assert!(run.status.success(), "{}", stderr(&run));
        let (doc, _) = stocking_glb(&out);
        let material = primitive(&doc, "leg").material();
        assert_eq!(material.name(), Some(want), "textured {textured}");
        if !textured {
            let pbr = material.pbr_metallic_roughness();
            assert_eq!(pbr.base_color_factor(), [0.5, 0.3, 0.2, 1.0]);
            assert_eq!(pbr.roughness_factor(), 0.7);
        }
    }
}

#[test]
fn the_stocking_surface_lies_clear_of_the_skin() {
    // Every stocking triangle sampled at its corners, edge midpoints and centre, against the
    // leg: at least the clearance a depth buffer resolves everywhere, so the leg's flat faces
    // never poke through and no viewer's depth test mixes the two (f32 positions: 1 µm).
    let legs = [
        (procedural_leg(), "60x60"),
        (sample(FEET[0]), "150x150"),
        (sample("makehuman_body.glb"), "150x150"),
    ];
    for (leg, grid) in legs {
        let (dir, report) = fit(&leg, grid, &[]);
        let (doc, buffers) = stocking_glb(&dir.path().join("out"));
        let stocking = primitive(&doc, "stocking");
        let reader = stocking.reader(|b| Some(&buffers[b.index()].0[..]));
        let positions: Vec<Point3<f64>> = reader
            .read_positions()
            .unwrap()
            .map(|p| Point3::new(p[0].into(), p[1].into(), p[2].into()))
            .collect();
        let indices: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
        let collider = collider_of(&leg);
        let (mut lowest, mut at, mut samples) = (f64::INFINITY, Point3::origin(), 0usize);
        let weights = [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.5, 0.5, 0.0],
            [0.0, 0.5, 0.5],
            [0.5, 0.0, 0.5],
            [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
        ];
        for t in indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| positions[t[k] as usize].coords);
            for [wa, wb, wc] in weights {
                let p = Point3::from(a * wa + b * wb + c * wc);
                let clearance = collider.closest(&p).signed_distance;
                samples += 1;
                if clearance < lowest {
                    (lowest, at) = (clearance, p);
                }
            }
        }
        let dipping = report.details.stocking_surface.unwrap().triangles_dipping;
        let triangles = indices.len() / 3;
        eprintln!(
            "{} {grid}: the stocking surface is at least {:.3} mm above the skin ({samples} \
             samples; lowest at {at:?}); {dipping} of {triangles} triangles closer than {} mm",
            leg.display(),
            1e3 * lowest,
            1e3 * STOCKING_CLEARANCE_M
        );
        // A handful in the toes' clefts, where lifting along the normals moves toward the next
        // toe, keep less; still far more than a depth buffer resolves (25 µm at 2 m).
        assert!(
            lowest > 0.2 * STOCKING_CLEARANCE_M,
            "{}: the stocking surface is {:.3} mm from the skin at {at:?}",
            leg.display(),
            1e3 * lowest
        );
        assert!(
            dipping * 1000 < triangles,
            "{}: {dipping} of {triangles} triangles dip",
            leg.display()
        );
    }
}
