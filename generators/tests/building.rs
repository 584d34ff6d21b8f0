//! Tests of the building generator: gradients against finite differences, mesh validity,
//! golden summaries per preset × level of detail, random parameter vectors, symmetry, bad
//! input.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

mod common;

use common::{Rng, check_gradient, check_range_corners, check_summary, random_params, validate};
use procfit_generators::building::{Building, idx};
use procfit_generators::{GenError, Generator, Lod};

/// Gradient check of a preset at a level; `moving` is how many continuous parameters change
/// the mesh there (a parameter that silently stops mattering is a regression too).
fn check_grad(preset: &str, lod: Lod, moving: usize) {
    let p = Building.preset(preset).expect("preset").values;
    let got = check_gradient(&Building, &p, lod, &format!("{preset} {lod:?}"));
    assert_eq!(
        got, moving,
        "{preset} {lod:?}: parameters that move the mesh"
    );
}

#[test]
fn vjp_matches_finite_differences_for_every_preset_at_two_lods() {
    // Medium: sizes, relief and roof; Ultra adds windows, frames, doors, stairs, balconies.
    // Parameters that do not move a preset: balcony sizes without balconies, the pitch of a
    // flat roof, the hip ridge of any roof but a hip, the wall-stripe width where no front
    // stripe is a wall.
    check_grad("panel_block", Lod::Medium, 10);
    check_grad("panel_block", Lod::Ultra, 23);
    check_grad("suburban_house", Lod::Medium, 11);
    check_grad("suburban_house", Lod::Ultra, 19);
    check_grad("office_block", Lod::Medium, 9);
    check_grad("office_block", Lod::Ultra, 17);
    check_grad("villa", Lod::Medium, 12);
    check_grad("villa", Lod::Ultra, 25);
    check_grad("tower", Lod::Medium, 11);
    check_grad("tower", Lod::Ultra, 24);
    check_grad("warehouse", Lod::Medium, 11);
    check_grad("warehouse", Lod::Ultra, 19);
    check_grad("townhouse_row", Lod::Medium, 11);
    check_grad("townhouse_row", Lod::Ultra, 19);
    check_grad("l_house", Lod::Medium, 13);
    check_grad("l_house", Lod::Ultra, 21);
    check_grad("shed_studio", Lod::Medium, 10);
    check_grad("shed_studio", Lod::Ultra, 18);
    // Every preset is covered above.
    assert_eq!(Building.presets().len(), 9);
}

#[test]
fn every_preset_and_lod_gives_a_valid_mesh() {
    for preset in Building.presets() {
        for lod in Lod::ALL {
            let m = Building.generate(&preset.values, lod).expect("generate");
            if let Err(e) = validate(&m) {
                panic!("{} {lod:?}: {e}", preset.name);
            }
        }
    }
}

#[test]
fn random_in_range_parameters_give_valid_meshes() {
    let mut rng = Rng::new(77);
    for case in 0..300 {
        let p = random_params(&Building, &mut rng);
        let lod = Lod::ALL[case % 4];
        let m = Building.generate(&p, lod).expect("generate");
        if let Err(e) = validate(&m) {
            panic!("case {case} {lod:?} {p:?}: {e}");
        }
    }
}

/// The index of the first vertex of `m` with no mirror image (to the millimetre) across the
/// plane x = 0 (`across_x`) or z = 0.
fn unmirrored(m: &procfit_generators::Mesh, across_x: bool) -> Option<usize> {
    let key = |x: f32, y: f32, z: f32| {
        (
            (x * 1e3).round() as i64,
            (y * 1e3).round() as i64,
            (z * 1e3).round() as i64,
        )
    };
    let set: std::collections::HashSet<_> =
        m.positions.iter().map(|p| key(p.x, p.y, p.z)).collect();
    m.positions.iter().position(|p| {
        let image = match across_x {
            true => key(-p.x, p.y, p.z),
            false => key(p.x, p.y, -p.z),
        };
        !set.contains(&image)
    })
}

#[test]
fn buildings_are_mirror_symmetric() {
    // Every vertex has a mirror image in x and in z (paper: symmetry planes YZ and XY).
    // An L footprint is not symmetric (its wing stands at one end), nor one chimney (no preset
    // has one); a shed roof is symmetric in x only (it rises to the back).
    for preset in Building.presets() {
        if preset.values[idx::FOOTPRINT] != 0.0 {
            continue;
        }
        let m = Building
            .generate(&preset.values, Lod::Ultra)
            .expect("generate");
        if let Some(i) = unmirrored(&m, true) {
            panic!("{}: no x-mirror of {}", preset.name, m.positions[i]);
        }
        let shed = preset.values[idx::ROOF_TYPE] == 3.0;
        if let Some(i) = unmirrored(&m, false).filter(|_| !shed) {
            panic!("{}: no z-mirror of {}", preset.name, m.positions[i]);
        }
    }
}

#[test]
fn chimneys_follow_their_layout_and_parameters() {
    let villa = Building.preset("villa").expect("villa").values;
    let base = Building.generate(&villa, Lod::Low).expect("generate");
    let wall_tris = |m: &procfit_generators::Mesh| m.tri_parts.iter().filter(|&&p| p == 0).count();
    // none, one, a pair, four: each chimney one closed box (12 triangles) of wall.
    for (layout, boxes) in [(0.0, 0), (1.0, 1), (2.0, 2), (3.0, 4)] {
        let mut p = villa.clone();
        p[idx::CHIMNEYS] = layout;
        let m = Building.generate(&p, Lod::Low).expect("generate");
        assert_eq!(
            wall_tris(&m),
            wall_tris(&base) + 12 * boxes,
            "layout {layout}"
        );
        if let Err(e) = validate(&m) {
            panic!("layout {layout}: {e}");
        }
    }
    // Their tops stand chimney_height above the eaves (the walls' top plus the fascia), above
    // everything else when tall; four are mirror images in x and z.
    let mut p = villa.clone();
    p[idx::CHIMNEYS] = 3.0;
    p[idx::CHIMNEY_HEIGHT] = 8.0;
    let m = Building.generate(&p, Lod::Ultra).expect("generate");
    let eaves = p[idx::BASE_HEIGHT]
        + p[idx::FLOORS] * p[idx::FLOOR_HEIGHT]
        + p[idx::TOP_HEIGHT]
        + p[idx::ROOF_BASE];
    let top = m.positions.iter().map(|v| v.y).fold(f32::MIN, f32::max);
    assert!(
        (f64::from(top) - eaves - 8.0).abs() < 1e-4,
        "top {top}, eaves {eaves}"
    );
    for across_x in [true, false] {
        if let Some(i) = unmirrored(&m, across_x) {
            panic!(
                "no mirror image of {} (across x: {across_x})",
                m.positions[i]
            );
        }
    }
    // Their position, size and height are differentiable: the villa's 12 moving parameters
    // at Medium and the four of the chimneys.
    let got = check_gradient(&Building, &p, Lod::Medium, "villa with four chimneys");
    assert_eq!(got, 16, "parameters that move the mesh");
}

#[test]
fn hip_ridge_lengthens_the_ridge_and_steepens_the_hip_ends() {
    // The ridge: the roof's highest vertices; its length along X.
    let ridge = |t: f64| {
        let mut p = Building.preset("villa").expect("villa").values;
        p[idx::HIP_RIDGE] = t;
        let m = Building.generate(&p, Lod::Low).expect("generate");
        let top = m.positions.iter().map(|v| v.y).fold(f32::MIN, f32::max);
        let xs: Vec<f32> = m
            .positions
            .iter()
            .filter(|v| (v.y - top).abs() < 1e-4)
            .map(|v| v.x)
            .collect();
        let len =
            xs.iter().fold(f32::MIN, |a, &b| a.max(b)) - xs.iter().fold(f32::MAX, |a, &b| a.min(b));
        (top, len)
    };
    let (h0, l0) = ridge(0.0);
    let (h1, l1) = ridge(0.5);
    // Same height (the pitch across the ridge is the sides'), a ridge longer by half the
    // half-depth on each end.
    let villa = Building.preset("villa").expect("villa").values;
    assert!((h0 - h1).abs() < 1e-4, "{h0} {h1}");
    assert!(
        ((l1 - l0) as f64 - villa[idx::DEPTH] * 0.5).abs() < 1e-3,
        "ridge {l0} -> {l1}, depth {}",
        villa[idx::DEPTH]
    );
}

#[test]
fn every_part_appears_at_ultra() {
    // The villa has windows, balconies, a door and stairs under a roof.
    let m = Building
        .generate(&Building.preset("villa").expect("villa").values, Lod::Ultra)
        .expect("generate");
    for (i, part) in m.parts.iter().enumerate() {
        assert!(m.tri_parts.contains(&(i as u8)), "no {}", part.name);
    }
    // LOW is a box and a roof only.
    let low = Building
        .generate(&Building.preset("villa").expect("villa").values, Lod::Low)
        .expect("generate");
    assert!(
        low.tri_parts
            .iter()
            .all(|&p| p == 0 || m.parts[usize::from(p)].name == "roof")
    );
}

/// Vertex count, triangle count and bounding box (min, max) of a preset at a level.
fn check(preset: &str, lod: Lod, verts: usize, tris: usize, lo: [f32; 3], hi: [f32; 3]) {
    check_summary(&Building, preset, lod, 1e-3, verts, tris, lo, hi);
}

#[test]
fn golden_summaries() {
    // Regenerate only for an intended change of the mesh; a surprise here is a regression.
    check(
        "panel_block",
        Lod::Low,
        16,
        24,
        [-23.4000, 0.0000, -6.4000],
        [23.4000, 14.7500, 6.4000],
    );
    check(
        "panel_block",
        Lod::Medium,
        112,
        168,
        [-23.4000, 0.0000, -6.4000],
        [23.4000, 14.7500, 6.4000],
    );
    check(
        "panel_block",
        Lod::High,
        1920,
        2880,
        [-23.4000, 0.0000, -7.2000],
        [23.4000, 14.7500, 7.2000],
    );
    check(
        "panel_block",
        Lod::Ultra,
        15824,
        23736,
        [-23.4000, 0.0000, -7.2000],
        [23.4000, 14.7500, 7.2000],
    );
    check(
        "suburban_house",
        Lod::Low,
        18,
        28,
        [-5.0000, 0.0000, -4.5000],
        [5.0000, 10.0658, 4.5000],
    );
    check(
        "suburban_house",
        Lod::Medium,
        114,
        172,
        [-5.0000, 0.0000, -4.5000],
        [5.0000, 10.0658, 4.5000],
    );
    check(
        "suburban_house",
        Lod::High,
        290,
        436,
        [-5.0000, 0.0000, -5.2000],
        [5.0000, 10.0658, 5.2000],
    );
    check(
        "suburban_house",
        Lod::Ultra,
        1666,
        2500,
        [-5.0000, 0.0000, -5.2000],
        [5.0000, 10.0658, 5.2000],
    );
    check(
        "office_block",
        Lod::Low,
        16,
        24,
        [-12.9000, 0.0000, -8.4000],
        [12.9000, 30.5500, 8.4000],
    );
    check(
        "office_block",
        Lod::Medium,
        80,
        120,
        [-12.9000, 0.0000, -8.4000],
        [12.9000, 30.5500, 8.4000],
    );
    check(
        "office_block",
        Lod::High,
        2544,
        3816,
        [-12.9000, 0.0000, -9.2000],
        [12.9000, 30.5500, 9.2000],
    );
    check(
        "office_block",
        Lod::Ultra,
        21872,
        32808,
        [-12.9000, 0.0000, -9.2000],
        [12.9000, 30.5500, 9.2000],
    );
    check(
        "villa",
        Lod::Low,
        18,
        28,
        [-9.9000, 0.0000, -6.8000],
        [9.9000, 11.8760, 6.8000],
    );
    check(
        "villa",
        Lod::Medium,
        82,
        124,
        [-9.9000, 0.0000, -6.8000],
        [9.9000, 11.8760, 6.8000],
    );
    check(
        "villa",
        Lod::High,
        514,
        772,
        [-9.9000, 0.0000, -7.2000],
        [9.9000, 11.8760, 7.2000],
    );
    check(
        "villa",
        Lod::Ultra,
        4306,
        6460,
        [-9.9000, 0.0000, -7.2000],
        [9.9000, 11.8760, 7.2000],
    );
    check(
        "tower",
        Lod::Low,
        16,
        24,
        [-9.1000, 0.0000, -8.4000],
        [9.1000, 30.2500, 8.4000],
    );
    check(
        "tower",
        Lod::Medium,
        112,
        168,
        [-9.1000, 0.0000, -8.4000],
        [9.1000, 30.2500, 8.4000],
    );
    check(
        "tower",
        Lod::High,
        2720,
        4080,
        [-9.8000, 0.0000, -9.2000],
        [9.8000, 30.2500, 9.2000],
    );
    check(
        "tower",
        Lod::Ultra,
        21376,
        32064,
        [-9.8000, 0.0000, -9.2000],
        [9.8000, 30.2500, 9.2000],
    );
    check(
        "warehouse",
        Lod::Low,
        18,
        28,
        [-16.8000, 0.0000, -9.3000],
        [16.8000, 7.3268, 9.3000],
    );
    check(
        "warehouse",
        Lod::Medium,
        178,
        268,
        [-16.8000, 0.0000, -9.3000],
        [16.8000, 7.3268, 9.3000],
    );
    check(
        "warehouse",
        Lod::High,
        338,
        508,
        [-16.8000, 0.0000, -11.0000],
        [16.8000, 7.3268, 11.0000],
    );
    check(
        "warehouse",
        Lod::Ultra,
        1394,
        2092,
        [-16.8000, 0.0000, -11.0000],
        [16.8000, 7.3268, 11.0000],
    );
    check(
        "townhouse_row",
        Lod::Low,
        18,
        28,
        [-9.9000, 0.0000, -5.2000],
        [9.9000, 15.6500, 5.2000],
    );
    check(
        "townhouse_row",
        Lod::Medium,
        146,
        220,
        [-9.9000, 0.0000, -5.2000],
        [9.9000, 15.6500, 5.2000],
    );
    check(
        "townhouse_row",
        Lod::High,
        530,
        796,
        [-9.9000, 0.0000, -6.2000],
        [9.9000, 15.6500, 6.2000],
    );
    check(
        "townhouse_row",
        Lod::Ultra,
        3698,
        5548,
        [-9.9000, 0.0000, -6.2000],
        [9.9000, 15.6500, 6.2000],
    );
}

#[test]
fn discrete_parameters_change_the_layout() {
    let base = Building.preset("panel_block").expect("panel").values;
    let count = |p: &[f64]| {
        Building
            .generate(p, Lod::Ultra)
            .expect("generate")
            .triangles
            .len()
    };
    let n = count(&base);
    for (i, v) in [
        (idx::FLOORS, 6.0),
        (idx::ENTRANCES, 3.0),
        (idx::BALCONY_BARS, 12.0),
        (idx::WINDOW_COLUMNS, 3.0),
    ] {
        let mut p = base.clone();
        p[i] = v;
        assert_ne!(count(&p), n, "parameter {i}");
    }
    // More floors make a taller building of the same floor height.
    let mut p = base.clone();
    p[idx::FLOORS] = 6.0;
    let h = |p: &[f64]| {
        Building
            .generate(p, Lod::Low)
            .expect("generate")
            .bounds()
            .expect("b")
            .1
            .y
    };
    assert!((h(&p) - h(&base) - 2.7).abs() < 1e-3);
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let mut p = Building.defaults();
    assert_eq!(
        Building.generate(&p[..7], Lod::Low).err(),
        Some(GenError::WrongLength {
            expected: idx::COUNT,
            got: 7
        })
    );
    p[idx::DEPTH] = f64::NAN;
    assert!(matches!(
        Building.generate(&p, Lod::Low),
        Err(GenError::NotFinite { name: "depth" })
    ));
    // Out of range and fractional counts are clamped and rounded.
    let mut wild = Building.defaults();
    wild[idx::FLOORS] = 99.4;
    wild[idx::ROOF_TYPE] = -3.0;
    let mut tame = Building.defaults();
    tame[idx::FLOORS] = 10.0;
    tame[idx::ROOF_TYPE] = 0.0;
    assert_eq!(
        Building.generate(&wild, Lod::High),
        Building.generate(&tame, Lod::High)
    );
}

#[test]
fn buildings_are_flat_shaded() {
    let m = Building
        .generate(&Building.preset("villa").expect("villa").values, Lod::Ultra)
        .expect("generate");
    for (t, tri) in m.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|i| m.positions[i as usize]);
        let face = (b - a).cross(c - a).normalize();
        for k in 0..3 {
            assert!(
                m.corner_normals[3 * t + k].dot(face) > 0.9999,
                "triangle {t}"
            );
        }
    }
}

#[test]
fn range_corners_give_valid_meshes() {
    check_range_corners(&Building);
}
