//! Part colours from the photos (issue 17): a synthetic photo of a mug of known part colours
//! (a blue body, a white handle, flat Lambert shading from one side, a clipped highlight, a
//! sticker under the don't-care brush, sensor noise) gives those colours back within
//! [`MAX_DELTA_E`] (CIE76); a part the photo does not show borrows its neighbour's colour; the
//! colours survive the params JSON, the GLB (its extras and `baseColorFactor`) and the OBJ's MTL.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

mod reconstruct_support;

use glam::Vec3;
use procfit::camera::View;
use procfit::colors::{self, PartColor, Rgba, Source, delta_e76, linear_to_srgb};
use procfit::export::{ExportOptions, Format, write_model};
use procfit::generators::{Lod, Mesh};
use procfit::mask::Mask;
use procfit::model::{Model, PartColors};
use procfit::optim::Rng;
use procfit::render::labels::LabelRenderer;
use reconstruct_support::{generator, mesh_of, random_view_at, render_mask, square_view};

/// The largest CIE76 ΔE*ab between a recovered colour and the truth (about 2.3 is the smallest
/// difference people notice side by side; 6 is "a close match" in print).
const MAX_DELTA_E: f64 = 6.0;
/// Shade levels of the synthetic photo.
const SHADES: u8 = 16;

const BLUE: [f32; 3] = [0.06, 0.22, 0.62];
const WHITE: [f32; 3] = [0.86, 0.86, 0.84];
const SIDE: u32 = 320;

/// A photo of `mesh` through `view`: part `p` in `albedo[p]` (linear), shaded
/// `0.5 + 0.5·max(0, n·sun)` per triangle, on a grey-brown textured table, with sensor noise;
/// sRGB 8-bit RGBA.
fn photo(mesh: &Mesh, view: &View, albedo: &[[f32; 3]]) -> Vec<u8> {
    let sun = Vec3::new(-0.5, 0.6, 0.62).normalize();
    let labels: Vec<u8> = mesh
        .triangles
        .iter()
        .zip(&mesh.tri_parts)
        .map(|(t, &part)| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let n = (b - a).cross(c - a).normalize_or(Vec3::Y);
            let shade = 0.5 + 0.5 * n.dot(sun).max(0.0);
            let level = ((shade * f32::from(SHADES)) as u8).min(SHADES - 1);
            part * SHADES + level
        })
        .collect();
    let n_labels = mesh.parts.len() * usize::from(SHADES);
    let mut r = LabelRenderer::new(view.width, view.height, 3).unwrap();
    let cov = r
        .render(&mesh.positions, &mesh.triangles, &labels, n_labels, view)
        .unwrap();
    let (w, h) = (view.width as usize, view.height as usize);
    let n = w * h;
    let mut rng = Rng::new(5);
    let mut out = vec![255u8; 4 * n];
    for i in 0..n {
        let (x, y) = (i % w, i / w);
        let grain = if (x / 7 + y / 5) % 2 == 0 { 0.30 } else { 0.24 };
        let mut rgb = [0.0f32; 3];
        let mut total = 0.0;
        for l in 0..n_labels {
            let c = cov[l * n + i];
            if c > 0.0 {
                let shade = (l % usize::from(SHADES)) as f32 / f32::from(SHADES);
                let part = l / usize::from(SHADES);
                for k in 0..3 {
                    rgb[k] += c * albedo[part][k] * shade;
                }
                total += c;
            }
        }
        let bg = [grain, grain * 0.9, grain * 0.75];
        for k in 0..3 {
            let v = rgb[k] + (1.0f32 - total).max(0.0) * bg[k];
            let noise = (rng.range(-1.0, 1.0) * 0.015) as f32;
            out[4 * i + k] = ((linear_to_srgb(v) + noise).clamp(0.0, 1.0) * 255.0).round() as u8;
        }
    }
    out
}

/// The mug preset with its handle, a camera that sees the handle, its mask and a photo.
fn scene(seed: u64) -> (Mesh, View, Mask, Vec<u8>) {
    let g = generator("dish");
    let mug = g.presets()[0].values.clone();
    let mesh = mesh_of("dish", &mug, Lod::High);
    let mut rng = Rng::new(seed);
    let params = random_view_at(&mut rng, &mesh, 0.7, 0.0);
    let view = square_view(params, SIDE);
    let mask = render_mask(&mesh, &params, SIDE);
    let part = |name: &str| mesh.parts.iter().position(|p| p.name == name).unwrap();
    let mut albedo = vec![[0.5f32; 3]; mesh.parts.len()];
    albedo[part("body")] = BLUE;
    albedo[part("handle")] = WHITE;
    let image = photo(&mesh, &view, &albedo);
    (mesh, view, mask, image)
}

fn colour_of<'a>(colors: &'a [PartColor], part: &str) -> &'a PartColor {
    colors.iter().find(|c| c.part == part).unwrap()
}

/// The pixels of the photo where the body is seen (mask object), for painting on.
fn object_pixels(mask: &Mask) -> Vec<usize> {
    (0..mask.values().len())
        .filter(|&i| mask.values()[i] == 1.0)
        .collect()
}

#[test]
fn a_blue_mug_with_a_white_handle_gives_its_colours_back() {
    for seed in [1, 2, 3] {
        let (mesh, view, mut mask, mut image) = scene(seed);
        let object = object_pixels(&mask);
        assert!(
            object.len() > 5_000,
            "the mug fills too little: {}",
            object.len()
        );
        // A clipped specular highlight: a 9 × 9 white patch at the object's centre of mass.
        let (mut cx, mut cy) = (0usize, 0usize);
        for &i in &object {
            cx += i % SIDE as usize;
            cy += i / SIDE as usize;
        }
        let (cx, cy) = (cx / object.len(), cy / object.len());
        for y in cy - 4..=cy + 4 {
            for x in cx - 4..=cx + 4 {
                let i = 4 * (y * SIDE as usize + x);
                image[i..i + 3].copy_from_slice(&[255, 255, 255]);
            }
        }
        // A red sticker that the user painted as don't-care: ignored.
        let mut values = mask.values().to_vec();
        for y in cy + 8..cy + 30 {
            for x in cx - 20..cx + 5 {
                let i = y * SIDE as usize + x;
                if values[i] == 1.0 {
                    image[4 * i..4 * i + 3].copy_from_slice(&[220, 20, 20]);
                    values[i] = Mask::DONT_CARE;
                }
            }
        }
        mask = Mask::new(SIDE, SIDE, values).unwrap();
        let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("colors");
        std::fs::create_dir_all(&dir).unwrap();
        image::save_buffer(
            dir.join(format!("mug-{seed}.png")),
            &image,
            SIDE,
            SIDE,
            image::ExtendedColorType::Rgba8,
        )
        .unwrap();
        let photo = Rgba {
            width: SIDE,
            height: SIDE,
            pixels: &image,
        };
        let got = colors::estimate(&mesh, &[view], &[photo], &[mask]).unwrap();
        let body = colour_of(&got, "body");
        let handle = colour_of(&got, "handle");
        let (db, dh) = (delta_e76(body.color, BLUE), delta_e76(handle.color, WHITE));
        println!(
            "seed {seed}: body {:?} ΔE {db:.2} ({:?}), handle {:?} ΔE {dh:.2} ({:?})",
            body.color, body.source, handle.color, handle.source
        );
        assert!(matches!(body.source, Source::Photo { .. }), "{body:?}");
        assert!(matches!(handle.source, Source::Photo { .. }), "{handle:?}");
        assert!(db <= MAX_DELTA_E, "seed {seed}: body ΔE {db:.2}");
        assert!(dh <= MAX_DELTA_E, "seed {seed}: handle ΔE {dh:.2}");
        // The generator's default (cream) is far from both: the test can tell.
        let default = mesh.parts[0].color;
        assert!(delta_e76([default[0], default[1], default[2]], BLUE) > 30.0);
    }
}

#[test]
fn a_part_the_photo_does_not_show_takes_its_neighbours_colour() {
    let (mesh, view, mask, image) = scene(1);
    // The user marks the handle don't-care: the photo no longer shows it.
    let mut r = LabelRenderer::new(SIDE, SIDE, 1).unwrap();
    let planes = r
        .render(
            &mesh.positions,
            &mesh.triangles,
            &mesh.tri_parts,
            mesh.parts.len(),
            &view,
        )
        .unwrap()
        .to_vec();
    let handle = mesh.parts.iter().position(|p| p.name == "handle").unwrap();
    let n = (SIDE * SIDE) as usize;
    let mut values = mask.values().to_vec();
    for (i, v) in values.iter_mut().enumerate() {
        // The handle and a pixel around it.
        let (x, y) = (i % SIDE as usize, i / SIDE as usize);
        let near = (y.saturating_sub(2)..(y + 3).min(SIDE as usize)).any(|yy| {
            (x.saturating_sub(2)..(x + 3).min(SIDE as usize))
                .any(|xx| planes[handle * n + yy * SIDE as usize + xx] > 0.0)
        });
        if near {
            *v = Mask::DONT_CARE;
        }
    }
    let mask = Mask::new(SIDE, SIDE, values).unwrap();
    let photo = Rgba {
        width: SIDE,
        height: SIDE,
        pixels: &image,
    };
    let got = colors::estimate(&mesh, &[view], &[photo], &[mask]).unwrap();
    let handle = colour_of(&got, "handle");
    assert_eq!(handle.source, Source::Neighbour("body"), "{handle:?}");
    assert_eq!(handle.color, colour_of(&got, "body").color);
    let note = colors::unseen_note(&got).unwrap();
    assert!(note.contains("handle took the colour of body"), "{note}");
    // Only parts with triangles are listed: this mug has no saucer.
    assert!(got.iter().all(|c| c.part != "saucer"), "{got:?}");
}

#[test]
fn mismatched_inputs_are_an_error_not_a_panic() {
    let (mesh, view, mask, image) = scene(1);
    let small = Rgba {
        width: 10,
        height: 10,
        pixels: &image[..400],
    };
    let e = colors::estimate(&mesh, &[view], &[small], std::slice::from_ref(&mask)).unwrap_err();
    assert!(e.0.contains("its photo is 10×10"), "{e}");
    let e = colors::estimate(&mesh, &[view], &[], &[mask]).unwrap_err();
    assert!(e.0.contains("one of each per view"), "{e}");
}

/// The mug with a blue body and a white handle, as the params JSON and GLB keep it.
fn coloured_mug() -> Model {
    let mut colors = PartColors::new();
    colors.insert("body".into(), BLUE);
    colors.insert("handle".into(), WHITE);
    let g = generator("dish");
    Model::new("dish", &g.presets()[0].values, Lod::Medium)
        .unwrap()
        .with_colors(&colors)
        .unwrap()
}

#[test]
fn colours_survive_params_json_glb_and_obj() {
    let model = coloured_mug();
    // Params JSON.
    let json = model.to_json();
    assert!(json.contains("\"colors\""), "{json}");
    let back = Model::from_json(&json).unwrap();
    assert_eq!(back.colors, model.colors);
    // GLB: the generator state in the extras, and each part's material.
    let glb = procfit::glb::export_model(&model, &[]).unwrap();
    let back = Model::from_file_bytes(&glb).unwrap();
    assert_eq!(back.colors, model.colors);
    let gltf = gltf::Gltf::from_slice(&glb).unwrap();
    for (part, want) in [("body", BLUE), ("handle", WHITE)] {
        let m = gltf
            .materials()
            .find(|m| m.name() == Some(part))
            .unwrap_or_else(|| panic!("no material {part}"));
        let c = m.pbr_metallic_roughness().base_color_factor();
        assert_eq!([c[0], c[1], c[2]], want, "{part}");
        assert_eq!(c[3], 1.0);
    }
    // OBJ + MTL: Kd is the colour.
    let (files, _) = write_model(
        &model,
        &[],
        Format::Obj,
        ExportOptions::default(),
        std::path::Path::new("mug.obj"),
    )
    .unwrap();
    let mtl = String::from_utf8(files.companion.unwrap()).unwrap();
    assert!(
        mtl.contains("newmtl body\nKa 0 0 0\nKd 0.06 0.22 0.62"),
        "{mtl}"
    );
    // A model without colours writes no `colors` at all (older readers are not surprised).
    let plain = Model::new("dish", &model.params, Lod::Medium).unwrap();
    assert!(!plain.to_json().contains("colors"));
}

#[test]
fn bad_colours_are_one_line_errors() {
    let g = generator("dish");
    let model = Model::new("dish", &g.presets()[0].values, Lod::Medium).unwrap();
    let mut doc = model.to_doc();
    doc.colors.insert("spout".into(), [0.1, 0.2, 0.3]);
    let e = Model::from_doc(&doc).unwrap_err();
    assert!(e.0.contains("dish has no part `spout` to colour"), "{e}");
    assert!(!e.0.contains('\n'));
    // Out of range is clamped, as parameters are.
    let mut doc = model.to_doc();
    doc.colors.insert("body".into(), [1.5, -0.2, 0.5]);
    assert_eq!(
        Model::from_doc(&doc).unwrap().colors["body"],
        [1.0, 0.0, 0.5]
    );
    // Not a number: the JSON parser says so.
    let json = model.to_json().replacen(
        "\"lod\"",
        "\"colors\": {\"body\": [\"blue\", 0, 0]}, \"lod\"",
        1,
    );
    assert!(Model::from_json(&json).is_err());
}
