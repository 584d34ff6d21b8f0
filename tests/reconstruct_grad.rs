//! The fit's objective against central finite differences: the camera values (through the
//! elevation/spin → renderer-angle conversion and the log-scale) and a few generator
//! parameters, on a small scene, plus the conventions of the camera helpers.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

mod reconstruct_support;

use procfit::generators::Lod;
use procfit::optim::{Objective, Rng};
use procfit::reconstruct::views::{ViewVars, fov_from_focal_35mm, mask_stats, renderer_angles};
use procfit::reconstruct::{FitObjective, Layout};
use reconstruct_support::*;

#[test]
fn objective_gradient_matches_finite_differences() {
    let mut rng = Rng::new(21);
    let x = random_dish(&mut rng, true);
    let mesh = mesh_of("dish", &x, Lod::Medium);
    let truth = random_view_at(&mut rng, &mesh, 0.5, 0.0);
    // 384²: coarser images make the finite differences of 8-bit anti-aliased coverage noisy.
    let mask = render_mask(&mesh, &truth, 384);
    let layout = Layout {
        n_gen: x.len(),
        n_views: 1,
        fit_fov: true,
        fov_y: vec![0.5],
    };
    let obj = FitObjective::new(
        generator("dish"),
        Lod::Medium,
        layout.clone(),
        vec![mask],
        1e-3,
        false,
    )
    .with_shape_prior(1e-3);
    // A point near, not at, the truth: a visible residual on every edge (the profile kinked
    // at its foot, so the shape prior's gradient counts too).
    let mut p = x.clone();
    p[0] += 0.3;
    p[9] *= 0.93;
    p.resize(layout.len(), 0.0);
    let vars = ViewVars {
        yaw: 0.35,
        pitch: 0.42,
        roll: 0.04,
        tx: truth.translation.x + 0.02,
        ty: truth.translation.y - 0.03,
        log_scale: truth.scale.ln() + 0.05,
        fov_y: 0.52,
    };
    layout.set_view_vars(&mut p, 0, &vars);
    let mut g = vec![0.0; p.len()];
    obj.value_grad(&p, &mut g);
    let o = layout.view_offset(0);
    // (index, step): camera values, then profile radii, y scale, handle thickness, centre and
    // a sweep radius. Measured agreement is 1–10 % (roll 25 % of a small value), limited by
    // the finite differences of quantised coverage, hence 15 % + 2e-3.
    let checks: Vec<(usize, f64)> = (0..7)
        .map(|k| (o + k, 1e-3))
        .chain([
            (0, 1e-2),
            (4, 1e-2),
            (8, 1e-2),
            (9, 1e-2),
            (11, 1e-3),
            (12, 1e-2),
            (20, 1e-2),
        ])
        .collect();
    check_finite_differences(|x| obj.value(x), &p, &g, &checks, 0.15);
}

#[test]
fn renderer_angles_reproduce_elevation_and_spin() {
    use glam::DMat3;
    let check = |yaw: f64, pitch: f64, roll: f64| {
        let want = DMat3::from_rotation_z(roll)
            * DMat3::from_rotation_x(pitch)
            * DMat3::from_rotation_y(yaw);
        let [a, b, c] = renderer_angles(yaw, pitch, roll);
        let got = DMat3::from_rotation_y(a) * DMat3::from_rotation_x(b) * DMat3::from_rotation_z(c);
        let err = (got - want)
            .abs()
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, &e| m.max(e));
        assert!(err < 1e-12, "({yaw}, {pitch}, {roll}) off by {err}");
    };
    check(0.0, 0.0, 0.0);
    check(0.5, 0.3, 0.0);
    check(-2.9, 1.2, 0.4);
    check(3.0, -0.5, -0.3);
    // With no spin the conversion is the identity.
    assert_eq!(renderer_angles(0.0, 0.4, 0.0), [0.0, 0.4, 0.0]);
}

#[test]
fn field_of_view_from_exif_focal_length() {
    let check = |f: f64, w: u32, h: u32, want: Option<f64>| {
        let got = fov_from_focal_35mm(f, w, h);
        match (got, want) {
            (Some(g), Some(w)) => assert!((g - w).abs() < 1e-3, "{f} mm {w}: {g}"),
            _ => assert_eq!(got, want),
        }
    };
    // 3:2 landscape = the 36 × 24 frame: vertical fov is 2·atan(12/f).
    check(50.0, 3000, 2000, Some(2.0 * (12.0f64 / 50.0).atan()));
    check(26.0, 3000, 2000, Some(2.0 * (12.0f64 / 26.0).atan()));
    // Portrait: the vertical side is the 36 mm one.
    check(50.0, 2000, 3000, Some(2.0 * (18.0f64 / 50.0).atan()));
    check(0.0, 10, 10, None);
    check(f64::NAN, 10, 10, None);
    check(50.0, 0, 10, None);
}

#[test]
fn mask_statistics_and_handle_side() {
    // A block with a thin arm on its right: the centroid sits left of the box centre, so the
    // generator's +X (handle) side goes to the right: yaw 0.
    let (w, h) = (40u32, 30u32);
    let v: Vec<f32> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let body = (5..20).contains(&x) && (5..25).contains(&y);
            let arm = (20..32).contains(&x) && (12..14).contains(&y);
            if body || arm { 1.0 } else { 0.0 }
        })
        .collect();
    let m = procfit::mask::Mask::new(w, h, v).unwrap();
    let s = mask_stats(&m, 0).unwrap();
    assert_eq!(
        (s.bbox_min.x, s.bbox_max.x, s.bbox_min.y, s.bbox_max.y),
        (5.0, 32.0, 5.0, 25.0)
    );
    assert_eq!(s.handle_yaw(), 0.0);
    let flipped: Vec<f32> = (0..w * h)
        .map(|i| m.values()[(i / w * w + (w - 1 - i % w)) as usize])
        .collect();
    let s = mask_stats(&procfit::mask::Mask::new(w, h, flipped).unwrap(), 0).unwrap();
    assert_eq!(s.handle_yaw(), std::f64::consts::PI);
}

/// A minimal EXIF block: IFD0 with an Exif-IFD pointer, the Exif IFD with
/// FocalLengthIn35mmFilm (SHORT) = `focal`.
fn exif_block(big_endian: bool, focal: u16) -> Vec<u8> {
    let u16b = |v: u16| {
        if big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let u32b = |v: u32| {
        if big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let mut b = Vec::new();
    b.extend_from_slice(if big_endian { b"MM" } else { b"II" });
    b.extend_from_slice(&u16b(42));
    b.extend_from_slice(&u32b(8));
    // IFD0 at 8: one entry, ExifIFDPointer (LONG) → 26.
    b.extend_from_slice(&u16b(1));
    b.extend_from_slice(&u16b(0x8769));
    b.extend_from_slice(&u16b(4));
    b.extend_from_slice(&u32b(1));
    b.extend_from_slice(&u32b(26));
    b.extend_from_slice(&u32b(0));
    // Exif IFD at 26: FocalLengthIn35mmFilm (SHORT).
    b.extend_from_slice(&u16b(1));
    b.extend_from_slice(&u16b(0xA405));
    b.extend_from_slice(&u16b(3));
    b.extend_from_slice(&u32b(1));
    b.extend_from_slice(&u16b(focal));
    b.extend_from_slice(&[0, 0]);
    b.extend_from_slice(&u32b(0));
    b
}

#[test]
fn focal_length_from_exif_blocks() {
    use procfit::reconstruct::views::focal_35mm_from_exif;
    assert_eq!(focal_35mm_from_exif(&exif_block(false, 26)), Some(26.0));
    assert_eq!(focal_35mm_from_exif(&exif_block(true, 50)), Some(50.0));
    let mut prefixed = b"Exif\0\0".to_vec();
    prefixed.extend(exif_block(false, 28));
    assert_eq!(focal_35mm_from_exif(&prefixed), Some(28.0));
    // Unknown (0), truncated at every length, garbage: no value and no panic.
    assert_eq!(focal_35mm_from_exif(&exif_block(false, 0)), None);
    // The value ends at byte 38 (Exif IFD at 26, count, tag, type, count, value).
    let full = exif_block(true, 50);
    for n in 0..38 {
        assert_eq!(focal_35mm_from_exif(&full[..n]), None, "truncated at {n}");
    }
    assert_eq!(focal_35mm_from_exif(&full[..38]), Some(50.0));
    assert_eq!(focal_35mm_from_exif(b"garbage bytes here"), None);
}

/// The focal length from a whole JPEG file (what the page reads from the original photo): a
/// small JPEG encoded here gets an APP1 `Exif` segment after SOI; without it there is none, and
/// bytes that are not an image give none either.
#[test]
fn focal_length_from_a_jpeg_file() {
    use procfit::reconstruct::views::focal_35mm_from_file;
    let img = image::RgbImage::from_fn(32, 24, |x, y| {
        image::Rgb([(x * 8) as u8, (y * 8) as u8, 90])
    });
    let mut plain = Vec::new();
    image::codecs::jpeg::JpegEncoder::new(&mut plain)
        .encode_image(&img)
        .unwrap();
    let mut app1 = b"Exif\0\0".to_vec();
    app1.extend(exif_block(false, 28));
    let mut with_exif = plain[..2].to_vec();
    with_exif.extend_from_slice(&[0xFF, 0xE1]);
    with_exif.extend_from_slice(&u16::try_from(app1.len() + 2).unwrap().to_be_bytes());
    with_exif.extend(app1);
    with_exif.extend_from_slice(&plain[2..]);
    assert_eq!(focal_35mm_from_file(&with_exif), Some(28.0));
    assert_eq!(focal_35mm_from_file(&plain), None);
    assert_eq!(focal_35mm_from_file(b"not an image at all"), None);
    assert_eq!(focal_35mm_from_file(&with_exif[..40]), None);
}

/// The rim term (`reconstruct::rim`) on a synthetic photo of a dish seen from 52° above: the
/// object bright, the inside of its rim dark, so the rim is an edge all round. Its value is
/// least at the true camera (a camera 9° lower with the same dish leaves the near rim off the
/// edge), and the objective's gradient with it matches central finite differences.
#[test]
fn rim_term_prefers_the_true_camera_and_its_gradient_matches_finite_differences() {
    use procfit::reconstruct::{Luma, RimTerm};

    let mut rng = Rng::new(5);
    let x = random_dish(&mut rng, false);
    let g = generator("dish");
    let lod = Lod::Medium;
    let mesh = mesh_of("dish", &x, lod);
    let side = 384u32;
    let truth = framing_view(&mesh, 0.3, 0.9);
    let view_of = |vars: &ViewVars| vars.view(side, side);
    let mask = render_mask(&mesh, &truth.params(), side);
    // The photo: background 0.5, object 0.8, inside the true rim's outline 0.3.
    let tv = view_of(&truth);
    let ring: Vec<glam::DVec2> = g.edge_rings(&x, lod)[0]
        .vertices
        .iter()
        .map(|&i| tv.project(mesh.positions[i as usize]).0)
        .collect();
    let luma = photo_with_dark_rim(&mask, &ring);
    // A photo with nothing inside the outline (a mask image sent as the photo): no term.
    let blank: Vec<u8> = mask
        .values()
        .iter()
        .flat_map(|&m| if m < 0.5 { [0, 0, 0, 255] } else { [255; 4] })
        .collect();
    let blank = Luma::from_rgba(side, side, &blank).unwrap();
    assert!(RimTerm::new(&[Some(blank)], std::slice::from_ref(&mask), 1.0).is_none());
    let photos = [Some(luma)];
    let term = RimTerm::new(&photos, std::slice::from_ref(&mask), 1.0).unwrap();
    let value =
        |vars: &ViewVars| term.evaluate(g, &x, lod, &mesh.positions, &[view_of(vars)], None);
    let at_truth = value(&truth);
    let lower = value(&ViewVars {
        pitch: truth.pitch - 0.15,
        ..truth
    });
    assert!(at_truth < 0.02, "rim term at the true camera {at_truth}");
    assert!(
        lower > at_truth + 0.05,
        "a lower camera {lower} vs the true one {at_truth}"
    );

    // The objective with the rim term, near the truth: silhouette and rim gradients together.
    let mut near = x.clone();
    near[8] *= 0.97;
    let (obj, p, grad, o) = with_rim_near(
        &near,
        mask,
        &photos,
        &ViewVars {
            pitch: truth.pitch - 0.04,
            ty: truth.ty + 0.01,
            ..truth
        },
    );
    // Steps that move the rim by a pixel or two: the edge's offset, found between the field's
    // samples, follows a point's motion only on average (measured: camera pitch and height
    // within 3–6 %, the rim radius 2 %, the object scale 45 %; the silhouette alone 4–30 %
    // at these steps).
    let checks = [
        (o + 1, 1e-2),
        (o + 4, 1e-2),
        (o + 5, 2e-2),
        (8, 5e-2),
        (9, 3e-2),
    ];
    check_finite_differences(|x| obj.value(x), &p, &grad, &checks, 0.35);
}

/// The foot of a cup on a saucer (the dish's second edge ring, `reconstruct::rim`): on a
/// synthetic photo from 40° above where the saucer is darker than the cup, the term at the true
/// camera finds the rim's and the foot's edges (near 0); on the same photo with the saucer as
/// bright as the cup, the foot finds no edge and costs about 1 a point; and the objective's
/// gradient with it, in the cup's foot radius and height and the camera, matches central finite
/// differences.
#[test]
fn the_foot_of_a_cup_on_a_saucer_is_read_where_the_cup_meets_the_saucer() {
    use procfit::reconstruct::{Luma, RimTerm};

    let g = generator("dish");
    let preset = |name: &str| {
        g.presets()
            .into_iter()
            .find(|p| p.name == name)
            .unwrap()
            .values
    };
    // The mug (straight walls: its foot faces a camera above) on the tea cup's saucer.
    let saucer = g
        .params()
        .iter()
        .position(|s| s.name == "has_saucer")
        .unwrap();
    let mut x = preset("mug");
    x[saucer..].copy_from_slice(&preset("tea_cup_on_saucer")[saucer..]);
    let lod = Lod::Medium;
    let mesh = mesh_of("dish", &x, lod);
    let rings = g.edge_rings(&x, lod);
    assert_eq!(rings.len(), 2, "the rim and the foot");
    let side = 384u32;
    let truth = framing_view(&mesh, 0.5, 0.7);
    let view_of = |vars: &ViewVars| vars.view(side, side);
    let mask = render_mask(&mesh, &truth.params(), side);
    // The cup alone: the body's and the handle's triangles (parts 0 and 1).
    let mut cup_mesh = mesh.clone();
    let kept: Vec<([u32; 3], u8)> = mesh
        .triangles
        .iter()
        .zip(&mesh.tri_parts)
        .filter(|(_, part)| **part <= 1)
        .map(|(t, p)| (*t, *p))
        .collect();
    cup_mesh.triangles = kept.iter().map(|k| k.0).collect();
    cup_mesh.tri_parts = kept.iter().map(|k| k.1).collect();
    let cup = render_mask(&cup_mesh, &truth.params(), side);
    let tv = view_of(&truth);
    let ring: Vec<glam::DVec2> = rings[0]
        .vertices
        .iter()
        .map(|&i| tv.project(mesh.positions[i as usize]).0)
        .collect();
    let value = |photo: Luma| {
        let term = RimTerm::new(&[Some(photo)], std::slice::from_ref(&mask), 1.0).unwrap();
        term.evaluate(g, &x, lod, &mesh.positions, &[tv], None)
    };
    let with_foot = value(photo_of_cup(&mask, &cup, &ring));
    let without = value(photo_with_dark_rim(&mask, &ring));
    assert!(with_foot < 0.05, "the term at the true camera {with_foot}");
    assert!(
        without > with_foot + 0.5,
        "no edge where the cup meets the saucer: {without} vs {with_foot}"
    );

    let photos = [Some(photo_of_cup(&mask, &cup, &ring))];
    let mut near = x.clone();
    near[0] *= 0.97;
    let (obj, p, grad, o) = with_rim_near(
        &near,
        mask,
        &photos,
        &ViewVars {
            pitch: truth.pitch - 0.03,
            ..truth
        },
    );
    // Steps that move the rings by a pixel or two (the height's silhouette gradient alone
    // bends beyond 3e-3: 0.0255 analytic, finite differences 0.0256 / 0.0218 / 0.0111 at
    // 3e-3 / 1e-2 / 3e-2).
    let checks = [(o + 1, 1e-2), (o + 5, 2e-2), (0, 1e-2), (9, 3e-3)];
    check_finite_differences(|x| obj.value(x), &p, &grad, &checks, 0.35);
}

/// The dish objective (medium detail, one view of `mask`) with the rim term of `photos` at
/// weight 1e-2, at the dish `x` seen through `view`: the objective, that point, the gradient
/// there and the view's offset in it.
fn with_rim_near(
    x: &[f64],
    mask: procfit::mask::Mask,
    photos: &[Option<procfit::reconstruct::Luma>],
    view: &ViewVars,
) -> (FitObjective, Vec<f64>, Vec<f64>, usize) {
    let layout = Layout {
        n_gen: x.len(),
        n_views: 1,
        fit_fov: false,
        fov_y: vec![0.5],
    };
    let rim = procfit::reconstruct::RimTerm::new(photos, std::slice::from_ref(&mask), 1e-2);
    let obj = FitObjective::new(
        generator("dish"),
        Lod::Medium,
        layout.clone(),
        vec![mask],
        0.0,
        false,
    )
    .with_rim(rim.map(std::sync::Arc::new));
    let mut p = x.to_vec();
    p.resize(layout.len(), 0.0);
    layout.set_view_vars(&mut p, 0, view);
    let mut grad = vec![0.0; p.len()];
    obj.value_grad(&p, &mut grad);
    (obj, p, grad, layout.view_offset(0))
}
