//! Tests of the dish generator: gradients against finite differences, mesh validity, golden
//! summaries per preset × level of detail, random parameter vectors, bad input.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

mod common;

use common::{Rng, check_gradient, check_range_corners, check_summary, random_params, validate};
use procfit_generators::dish::{self, Dish};
use procfit_generators::{GenError, Generator, Lod};

#[test]
fn vjp_matches_finite_differences_for_every_preset_at_two_lods() {
    let n_handle = 2 + 2 * dish::HANDLE_STEPS;
    for preset in Dish.presets() {
        for lod in [Lod::Low, Lod::Medium] {
            let what = format!("{} {lod:?}", preset.name);
            let moving = check_gradient(&Dish, &preset.values, lod, &what);
            // Every body parameter moves the mesh; with a handle, every handle parameter too,
            // and with a saucer its three continuous parameters.
            let has_handle = preset.values[dish::P_HAS_HANDLE] > 0.5;
            let has_saucer = preset.values[dish::P_HAS_SAUCER] > 0.5;
            let expected =
                10 + if has_handle { n_handle } else { 0 } + if has_saucer { 3 } else { 0 };
            assert_eq!(moving, expected, "{what}: parameters that move the mesh");
        }
    }
}

#[test]
fn every_preset_and_lod_gives_a_valid_mesh() {
    for preset in Dish.presets() {
        for lod in Lod::ALL {
            let m = Dish.generate(&preset.values, lod).expect("generate");
            if let Err(e) = validate(&m) {
                panic!("{} {lod:?}: {e}", preset.name);
            }
            let has_handle = preset.values[dish::P_HAS_HANDLE] > 0.5;
            assert_eq!(m.tri_parts.contains(&1), has_handle, "{}", preset.name);
            let has_saucer = preset.values[dish::P_HAS_SAUCER] > 0.5;
            assert_eq!(m.tri_parts.contains(&2), has_saucer, "{}", preset.name);
        }
    }
}

#[test]
fn random_in_range_parameters_give_valid_meshes() {
    let mut rng = Rng::new(2024);
    for case in 0..300 {
        let p = random_params(&Dish, &mut rng);
        let lod = if case % 10 == 0 {
            Lod::Medium
        } else {
            Lod::Low
        };
        let m = Dish.generate(&p, lod).expect("generate");
        if let Err(e) = validate(&m) {
            panic!("case {case} {lod:?} {p:?}: {e}");
        }
    }
}

/// The first of `Dish::edge_rings`, the rim, is where the body's rounded top meets its inside:
/// consecutive vertices at one height, within a wall of the body's top, on a circle around the
/// axis on the inner side of the lip's apex, going once around it; for every preset and level,
/// and for random dishes.
#[test]
fn the_rim_is_where_the_top_of_the_body_meets_its_inside() {
    let mut rng = Rng::new(7);
    let mut cases: Vec<(String, Vec<f64>, Lod)> = Vec::new();
    for preset in Dish.presets() {
        for lod in Lod::ALL {
            cases.push((preset.name.to_string(), preset.values.clone(), lod));
        }
    }
    for k in 0..40 {
        cases.push((
            format!("random {k}"),
            random_params(&Dish, &mut rng),
            Lod::Low,
        ));
    }
    for (what, p, lod) in cases {
        let m = Dish.generate(&p, lod).expect("generate");
        let rim = Dish.edge_rings(&p, lod)[0].vertices.clone();
        assert_eq!(rim.len(), 12 << lod.index(), "{what} {lod:?}");
        // The body is part 0: the highest of its vertices.
        let mut body = vec![false; m.positions.len()];
        for (t, tri) in m.triangles.iter().enumerate() {
            if m.tri_parts[t] == 0 {
                for &v in tri {
                    body[v as usize] = true;
                }
            }
        }
        let top = (0..m.positions.len())
            .filter(|&i| body[i])
            .map(|i| m.positions[i].y)
            .fold(f32::MIN, f32::max);
        let radius = |i: u32| m.positions[i as usize].x.hypot(m.positions[i as usize].z);
        let r0 = radius(rim[0]);
        let mut turn = 0.0f32;
        for (k, &i) in rim.iter().enumerate() {
            assert!(
                body[i as usize],
                "{what} {lod:?}: rim vertex {i} is not the body's"
            );
            let p = m.positions[i as usize];
            // The half circle's inner end: half a wall below its apex on a straight wall; a
            // flared wall (a plate's is almost flat) tilts the lip, so it may lie higher.
            let wall = dish::WALL as f32;
            assert!(
                (p.y - top).abs() < wall,
                "{what} {lod:?}: rim at {} below the top {top}",
                p.y
            );
            // On the lip's inner side: no further out than the body's highest ring (the lip's
            // apex on a straight wall; on a flared one the inner end itself may be highest),
            // and within a wall of it.
            let apex = (0..m.positions.len())
                .filter(|&j| body[j] && m.positions[j].y > top - 1e-6)
                .map(|j| radius(j as u32))
                .fold(f32::MIN, f32::max);
            let inset = apex - radius(i);
            assert!(
                inset > -1e-5 && inset < wall,
                "{what} {lod:?}: the rim {inset} inside the lip's apex"
            );
            assert!(
                (radius(i) - r0).abs() < 1e-5 * r0.max(1.0),
                "{what} {lod:?}: not a circle"
            );
            let q = m.positions[rim[(k + 1) % rim.len()] as usize];
            let d = q.z.atan2(q.x) - p.z.atan2(p.x);
            turn +=
                (d + std::f32::consts::PI).rem_euclid(std::f32::consts::TAU) - std::f32::consts::PI;
        }
        assert!(
            (turn.abs() - std::f32::consts::TAU).abs() < 1e-3,
            "{what} {lod:?}: turns {turn}"
        );
    }
    // On a straight wall (the mug) the ring is the lip's inner end, half a wall inside its
    // apex and half a wall below it, not the apex itself.
    let mug = Dish.preset("mug").expect("mug").values;
    let m = Dish.generate(&mug, Lod::High).expect("generate");
    let rim = &Dish.edge_rings(&mug, Lod::High)[0].vertices;
    let top = m.positions.iter().map(|p| p.y).fold(f32::MIN, f32::max);
    let apex = m
        .positions
        .iter()
        .filter(|p| p.y > top - 1e-6)
        .map(|p| p.x.hypot(p.z))
        .fold(f32::MIN, f32::max);
    let half = 0.5 * dish::WALL as f32;
    for &i in rim {
        let p = m.positions[i as usize];
        assert!((apex - p.x.hypot(p.z) - half).abs() < 0.2 * half, "{p}");
        assert!((top - p.y - half).abs() < 0.2 * half, "{p}");
    }
}

/// With a saucer, the second edge ring is the cup's foot (the outer wall's lowest ring, the
/// bottom corner's height above the saucer's well, and the rings above it up the outer surface,
/// below half the cup's height) seen within the saucer rim's top ring (the saucer's highest ring); without one, there
/// is only the rim. Every preset
/// with a saucer and random dishes with and without a handle, at every level.
#[test]
fn the_foot_of_a_cup_on_a_saucer_is_an_edge_ring_seen_within_the_saucer_rim() {
    let mut rng = Rng::new(11);
    let mut cases: Vec<(String, Vec<f64>)> = Dish
        .presets()
        .into_iter()
        .map(|p| (p.name.to_string(), p.values))
        .collect();
    for k in 0..30 {
        let mut p = random_params(&Dish, &mut rng);
        p[dish::P_HAS_SAUCER] = if k % 3 == 0 { 0.0 } else { 1.0 };
        p[dish::P_HAS_HANDLE] = if k % 2 == 0 { 0.0 } else { 1.0 };
        cases.push((format!("random {k}"), p));
    }
    let mut with_saucer = 0;
    for (what, p) in cases {
        for lod in Lod::ALL {
            let m = Dish.generate(&p, lod).expect("generate");
            let rings = Dish.edge_rings(&p, lod);
            if p[dish::P_HAS_SAUCER] <= 0.5 {
                assert_eq!(rings.len(), 1, "{what} {lod:?}: only the rim");
                continue;
            }
            with_saucer += 1;
            assert_eq!(rings.len(), 2, "{what} {lod:?}: the rim and the foot");
            let foot = &rings[1];
            let n = 12 << lod.index();
            assert_eq!(foot.vertices.len(), n, "{what} {lod:?}");
            assert_eq!(foot.seen_within.len(), n, "{what} {lod:?}");
            let mut parts = vec![u8::MAX; m.positions.len()];
            for (tri, &part) in m.triangles.iter().zip(&m.tri_parts) {
                for &v in tri {
                    parts[v as usize] = part;
                }
            }
            let part_of = |v: u32| parts[v as usize];
            let pos = |v: u32| m.positions[v as usize];
            let radius = |v: u32| pos(v).x.hypot(pos(v).z);
            // Body vertices on the saucer's part: the lowest of the body's outer wall.
            let body_min_y = (0..m.positions.len() as u32)
                .filter(|&v| part_of(v) == 0)
                .map(|v| pos(v).y)
                .fold(f32::MAX, f32::min);
            let body_top = (0..m.positions.len() as u32)
                .filter(|&v| part_of(v) == 0)
                .map(|v| pos(v).y)
                .fold(f32::MIN, f32::max);
            let saucer: Vec<u32> = (0..m.positions.len() as u32)
                .filter(|&v| part_of(v) != 0 && part_of(v) != 1)
                .collect();
            let saucer_top = saucer.iter().map(|&v| pos(v).y).fold(f32::MIN, f32::max);
            assert!(
                !foot.above.is_empty(),
                "{what} {lod:?}: the rings above the foot"
            );
            let same_angle = |u: u32, v: u32| {
                (pos(u).z.atan2(pos(u).x) - pos(v).z.atan2(pos(v).x)).abs() < 1e-3
                    || radius(u) < 1e-6
            };
            for k in 0..n {
                let (f, s) = (foot.vertices[k], foot.seen_within[k]);
                assert_eq!(part_of(f), 0, "{what} {lod:?}: the foot is the body's");
                assert!(
                    (pos(f).y - body_min_y - dish::CORNER as f32).abs() < 1e-4,
                    "{what} {lod:?}: the foot at {} above the body's bottom {body_min_y}",
                    pos(f).y
                );
                let mut below = f;
                for ring in &foot.above {
                    assert_eq!(ring.len(), n, "{what} {lod:?}");
                    let a = ring[k];
                    assert_eq!(part_of(a), 0, "{what} {lod:?}: the body's outer surface");
                    assert!(pos(a).y > pos(below).y, "{what} {lod:?}: going up");
                    assert!(same_angle(f, a), "{what} {lod:?}: sector {k}");
                    below = a;
                }
                // Up the lower part of the wall: below the middle of the wall.
                assert!(
                    pos(below).y < body_min_y + 0.5 * (body_top - body_min_y),
                    "{what} {lod:?}: the band reaches {} of {body_top}",
                    pos(below).y
                );
                assert!(saucer.contains(&s), "{what} {lod:?}: the saucer's rim");
                assert!(
                    (pos(s).y - saucer_top).abs() < 1e-4,
                    "{what} {lod:?}: the saucer ring at {} below its top {saucer_top}",
                    pos(s).y
                );
                assert!(radius(s) > radius(f), "{what} {lod:?}: around the foot");
                assert!(same_angle(f, s), "{what} {lod:?}: sector {k}");
            }
        }
    }
    assert!(with_saucer >= 20, "{with_saucer} cases with a saucer");
}

/// Vertex count, triangle count and bounding box (min, max) of a preset at a level.
fn check(preset: &str, lod: Lod, verts: usize, tris: usize, lo: [f32; 3], hi: [f32; 3]) {
    check_summary(&Dish, preset, lod, 1e-4, verts, tris, lo, hi);
}

#[test]
fn golden_summaries() {
    // Regenerate only for an intended change of the mesh; a surprise here is a regression.
    check(
        "mug",
        Lod::Low,
        592,
        1176,
        [-0.3603, 0.0000, -0.3603],
        [0.6740, 0.9125, 0.3603],
    );
    check(
        "mug",
        Lod::Medium,
        2140,
        4272,
        [-0.3603, 0.0000, -0.3603],
        [0.6740, 0.9125, 0.3603],
    );
    check(
        "mug",
        Lod::High,
        8116,
        16224,
        [-0.3603, 0.0000, -0.3603],
        [0.6740, 0.9125, 0.3603],
    );
    check(
        "mug",
        Lod::Ultra,
        31588,
        63168,
        [-0.3604, 0.0000, -0.3604],
        [0.6740, 0.9125, 0.3604],
    );
    check(
        "tea_cup",
        Lod::Low,
        592,
        1176,
        [-0.4680, 0.0000, -0.4680],
        [0.6456, 0.6439, 0.4680],
    );
    check(
        "tea_cup",
        Lod::Medium,
        2140,
        4272,
        [-0.4680, 0.0000, -0.4680],
        [0.6456, 0.6439, 0.4680],
    );
    check(
        "tea_cup",
        Lod::High,
        8116,
        16224,
        [-0.4680, 0.0000, -0.4680],
        [0.6456, 0.6439, 0.4680],
    );
    check(
        "tea_cup",
        Lod::Ultra,
        31588,
        63168,
        [-0.4681, 0.0000, -0.4681],
        [0.6456, 0.6440, 0.4681],
    );
    check(
        "bowl",
        Lod::Low,
        470,
        936,
        [-0.5310, 0.0000, -0.5310],
        [0.5310, 0.5083, 0.5310],
    );
    check(
        "bowl",
        Lod::Medium,
        1898,
        3792,
        [-0.5310, 0.0000, -0.5310],
        [0.5310, 0.5083, 0.5310],
    );
    check(
        "bowl",
        Lod::High,
        7634,
        15264,
        [-0.5310, 0.0000, -0.5310],
        [0.5310, 0.5084, 0.5310],
    );
    check(
        "bowl",
        Lod::Ultra,
        30626,
        61248,
        [-0.5310, 0.0000, -0.5310],
        [0.5310, 0.5084, 0.5310],
    );
    check(
        "plate",
        Lod::Low,
        470,
        936,
        [-0.5878, 0.0000, -0.5878],
        [0.5878, 0.1283, 0.5878],
    );
    check(
        "plate",
        Lod::Medium,
        1898,
        3792,
        [-0.5900, 0.0000, -0.5900],
        [0.5900, 0.1305, 0.5900],
    );
    check(
        "plate",
        Lod::High,
        7634,
        15264,
        [-0.5900, 0.0000, -0.5900],
        [0.5900, 0.1305, 0.5900],
    );
    check(
        "plate",
        Lod::Ultra,
        30626,
        61248,
        [-0.5902, 0.0000, -0.5902],
        [0.5902, 0.1306, 0.5902],
    );
    check(
        "tumbler",
        Lod::Low,
        470,
        936,
        [-0.2970, 0.0000, -0.2970],
        [0.2970, 1.0480, 0.2970],
    );
    check(
        "tumbler",
        Lod::Medium,
        1898,
        3792,
        [-0.2970, 0.0000, -0.2970],
        [0.2970, 1.0480, 0.2970],
    );
    check(
        "tumbler",
        Lod::High,
        7634,
        15264,
        [-0.2970, 0.0000, -0.2970],
        [0.2970, 1.0480, 0.2970],
    );
    check(
        "tumbler",
        Lod::Ultra,
        30626,
        61248,
        [-0.2970, 0.0000, -0.2970],
        [0.2970, 1.0480, 0.2970],
    );
    check(
        "vase",
        Lod::Low,
        470,
        936,
        [-0.4258, 0.0000, -0.4258],
        [0.4258, 1.1411, 0.4258],
    );
    check(
        "vase",
        Lod::Medium,
        1898,
        3792,
        [-0.4260, 0.0000, -0.4260],
        [0.4260, 1.1410, 0.4260],
    );
    check(
        "vase",
        Lod::High,
        7634,
        15264,
        [-0.4264, 0.0000, -0.4264],
        [0.4264, 1.1416, 0.4264],
    );
    check(
        "vase",
        Lod::Ultra,
        30626,
        61248,
        [-0.4264, 0.0000, -0.4264],
        [0.4264, 1.1415, 0.4264],
    );
    check(
        "mug_ear_handle",
        Lod::Low,
        592,
        1176,
        [-0.3603, 0.0000, -0.3603],
        [0.6798, 0.9125, 0.3603],
    );
    check(
        "mug_ear_handle",
        Lod::Medium,
        2140,
        4272,
        [-0.3603, 0.0000, -0.3603],
        [0.6798, 0.9125, 0.3603],
    );
    check(
        "mug_ear_handle",
        Lod::High,
        8116,
        16224,
        [-0.3603, 0.0000, -0.3603],
        [0.6798, 0.9125, 0.3603],
    );
    check(
        "mug_ear_handle",
        Lod::Ultra,
        31588,
        63168,
        [-0.3604, 0.0000, -0.3604],
        [0.6798, 0.9125, 0.3604],
    );
    check(
        "mug_square_handle",
        Lod::Low,
        592,
        1176,
        [-0.3603, 0.0000, -0.3603],
        [0.6341, 0.9125, 0.3603],
    );
    check(
        "mug_square_handle",
        Lod::Medium,
        2140,
        4272,
        [-0.3603, 0.0000, -0.3603],
        [0.6341, 0.9125, 0.3603],
    );
    check(
        "mug_square_handle",
        Lod::High,
        8116,
        16224,
        [-0.3603, 0.0000, -0.3603],
        [0.6341, 0.9125, 0.3603],
    );
    check(
        "mug_square_handle",
        Lod::Ultra,
        31588,
        63168,
        [-0.3604, 0.0000, -0.3604],
        [0.6341, 0.9125, 0.3604],
    );
    check(
        "mug_small_handle",
        Lod::Low,
        592,
        1176,
        [-0.3603, 0.0000, -0.3603],
        [0.5424, 0.9125, 0.3603],
    );
    check(
        "mug_small_handle",
        Lod::Medium,
        2140,
        4272,
        [-0.3603, 0.0000, -0.3603],
        [0.5424, 0.9125, 0.3603],
    );
    check(
        "mug_small_handle",
        Lod::High,
        8116,
        16224,
        [-0.3603, 0.0000, -0.3603],
        [0.5424, 0.9125, 0.3603],
    );
    check(
        "mug_small_handle",
        Lod::Ultra,
        31588,
        63168,
        [-0.3604, 0.0000, -0.3604],
        [0.5424, 0.9125, 0.3604],
    );
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let mut p = Dish.defaults();
    assert_eq!(
        Dish.generate(&p[..5], Lod::Low).err(),
        Some(GenError::WrongLength {
            expected: dish::N_PARAMS,
            got: 5
        })
    );
    p[3] = f64::NAN;
    assert!(matches!(
        Dish.generate(&p, Lod::Low),
        Err(GenError::NotFinite { .. })
    ));
    p[3] = f64::INFINITY;
    assert!(Dish.generate_with_vjp(&p, Lod::Low).is_err());
    // Out of range is clamped: the same mesh as the range end.
    let mut big = Dish.defaults();
    big[dish::P_Y_SCALE] = 1e9;
    let mut end = Dish.defaults();
    end[dish::P_Y_SCALE] = 1.25;
    assert_eq!(Dish.generate(&big, Lod::Low), Dish.generate(&end, Lod::Low));
    // A wrong adjoint length is an error.
    let (_, vjp) = Dish.generate_with_vjp(&end, Lod::Low).expect("vjp");
    let mut g = vec![0.0; dish::N_PARAMS];
    assert!(vjp.vjp(&[glam::Vec3::ZERO; 3], &mut g).is_err());
}

#[test]
fn seeds_are_bodies_times_handles_plus_handleless() {
    let seeds = Dish.seeds();
    assert_eq!(seeds.len(), 6 * 4 + 6);
    let with_handle = seeds.iter().filter(|s| s[dish::P_HAS_HANDLE] > 0.5).count();
    assert_eq!(with_handle, 24);
    assert!(seeds.iter().all(|s| s[dish::P_HAS_SAUCER] < 0.5));
    let (extras, own) = Dish.extra_seeds();
    assert_eq!(extras.len(), 4);
    assert_eq!(own, dish::P_HAS_SAUCER..dish::N_PARAMS);
    assert!(extras.iter().all(|s| s[dish::P_HAS_SAUCER] > 0.5));
    for s in &seeds {
        assert_eq!(
            procfit_generators::sanitize_params(Dish.params(), s).as_ref(),
            Ok(s)
        );
    }
}

#[test]
fn regularizer_gradient_matches_finite_differences() {
    let mut rng = Rng::new(11);
    for _ in 0..20 {
        let mut p = random_params(&Dish, &mut rng);
        p[dish::P_HAS_HANDLE] = 1.0;
        penalty_gradient_matches_finite_differences(|p| Dish.regularizer(p), &p);
    }
    // The penalties fire where the notes say: a narrowing profile, a rim > 3× the base, a
    // jumpy handle. A straight mug with a smooth handle costs nothing.
    let mug = Dish.preset("mug").expect("mug").values;
    let (base, _) = Dish.regularizer(&mug);
    let mut narrowing = mug.clone();
    narrowing[dish::P_RADIUS + 8] = 2.0;
    let mut flared = mug.clone();
    flared[dish::P_RADIUS] = 1.0;
    let mut jumpy = mug.clone();
    jumpy[dish::P_SWEEP + 5] = 0.5;
    for (what, p) in [
        ("narrowing", narrowing),
        ("flared", flared),
        ("jumpy", jumpy),
    ] {
        assert!(Dish.regularizer(&p).0 > base + 0.01, "{what}");
    }
}

/// The shape prior (the profile's kinks): its gradient against central differences, and where
/// it fires. Every preset's smooth wall costs little (the vase most, its neck); a tea cup whose
/// lower half is a narrow cylinder under a bowl costs more than the same cup with a steady
/// curve, and a mug on a narrow foot more than the mug; a straight or steadily curving wall
/// costs nothing.
#[test]
fn the_shape_prior_finds_kinks_in_the_wall() {
    let mut rng = Rng::new(12);
    for _ in 0..20 {
        let p = random_params(&Dish, &mut rng);
        penalty_gradient_matches_finite_differences(|p| Dish.shape_prior(p), &p);
    }
    for preset in Dish.presets() {
        let (v, _) = Dish.shape_prior(&preset.values);
        assert!(v < 1.5, "{}: {v}", preset.name);
    }
    let mut curve = Dish.preset("mug").expect("mug").values;
    for (i, r) in curve[dish::P_RADIUS..dish::P_RADIUS + 9]
        .iter_mut()
        .enumerate()
    {
        *r = 3.0 + 0.2 * i as f64 + 0.03 * (i * i) as f64;
    }
    assert!(Dish.shape_prior(&curve).0 < 1e-12, "a steady curve");
    let tea_cup = Dish.preset("tea_cup").expect("tea_cup").values;
    let mut stepped = tea_cup.clone();
    stepped[dish::P_RADIUS..dish::P_RADIUS + 9]
        .copy_from_slice(&[3.0, 3.0, 3.0, 3.0, 4.8, 4.9, 5.0, 5.1, 5.2]);
    let mug = Dish.preset("mug").expect("mug").values;
    let mut on_a_foot = mug.clone();
    on_a_foot[dish::P_RADIUS] = 2.0;
    for (what, p, smooth) in [
        ("stepped", stepped, &tea_cup),
        ("on a foot", on_a_foot, &mug),
    ] {
        let (v, s) = (Dish.shape_prior(&p).0, Dish.shape_prior(smooth).0);
        assert!(v > s + 1.0, "{what}: {v} against {s}");
    }
}

/// The shape prior's saucer proportion: the tea cup on its saucer (rim 0.244 of the saucer's
/// radius high, as measured saucers) costs little for it; the same saucer half as high costs,
/// and the prior's gradient raises its rim; twice as wide at the same height costs alike (the
/// ratio, not the height, is the prior: a saucer keeps its proportions under a small cup).
#[test]
fn the_shape_prior_keeps_a_saucer_as_high_as_real_ones() {
    let cup = Dish.preset("tea_cup_on_saucer").expect("preset").values;
    let without = |p: &[f64]| {
        let mut bare = p.to_vec();
        bare[dish::P_HAS_SAUCER] = 0.0;
        Dish.shape_prior(&bare).0
    };
    let rise = |p: &[f64]| {
        p[dish::P_SAUCER_HEIGHT] * dish::HEIGHT_UNIT
            / (p[dish::P_SAUCER_RADIUS] * p[dish::P_RADIUS] * dish::RADIUS_UNIT)
    };
    assert!(
        (rise(&cup) - dish::SAUCER_RISE).abs() < 0.01,
        "{}",
        rise(&cup)
    );
    assert!(Dish.shape_prior(&cup).0 - without(&cup) < 0.1);
    let mut flat = cup.clone();
    flat[dish::P_SAUCER_HEIGHT] *= 0.5;
    let (v, g) = Dish.shape_prior(&flat);
    let extra = v - without(&flat);
    let expected = dish::SAUCER_RISE_WEIGHT * (0.5 * rise(&cup) - dish::SAUCER_RISE).powi(2);
    assert!(
        (extra - expected).abs() < 1e-6 * expected,
        "{extra} against {expected}"
    );
    assert!(g[dish::P_SAUCER_HEIGHT] < 0.0, "descent raises the rim");
    let mut wide = cup.clone();
    wide[dish::P_SAUCER_RADIUS] *= 2.0;
    let wide_extra = Dish.shape_prior(&wide).0 - without(&wide);
    assert!(
        (wide_extra - extra).abs() < 1e-6 * extra,
        "{wide_extra} against {extra}"
    );
    penalty_gradient_matches_finite_differences(|p| Dish.shape_prior(p), &flat);
}

/// A penalty of the dish (value, gradient) at `p`: non-negative, and its gradient in every
/// continuous parameter within 1e-5 (relative) of central differences that stay in range.
fn penalty_gradient_matches_finite_differences(
    penalty: impl Fn(&[f64]) -> (f64, Vec<f64>),
    p: &[f64],
) {
    let (v, g) = penalty(p);
    assert!(v >= 0.0);
    for (i, s) in Dish.params().iter().enumerate() {
        let h = 1e-6;
        let (mut a, mut b) = (p.to_vec(), p.to_vec());
        a[i] += h;
        b[i] -= h;
        if !s.kind.is_continuous() || a[i] > s.max || b[i] < s.min {
            continue;
        }
        let fd = (penalty(&a).0 - penalty(&b).0) / (2.0 * h);
        assert!(
            (fd - g[i]).abs() < 1e-5 * (1.0 + fd.abs()),
            "{}: {fd} vs {}",
            s.name,
            g[i]
        );
    }
}

/// Which vertices belong to the body (part 0).
trait BodyVertices {
    fn body_vertices(&self) -> Vec<bool>;
}

impl BodyVertices for procfit_generators::Mesh {
    fn body_vertices(&self) -> Vec<bool> {
        let mut body = vec![false; self.positions.len()];
        for (t, &part) in self.triangles.iter().zip(&self.tri_parts) {
            if part == 0 {
                for &i in t {
                    body[i as usize] = true;
                }
            }
        }
        body
    }
}

#[test]
fn handle_ends_sink_into_the_wall() {
    // The centres of both end caps (the mesh's last two vertices, by construction) lie inside
    // the outer wall at their height, whatever the body: the snap to the wall works for
    // narrow, wide, flared and bulging bodies alike.
    let handles = dish::handle_shapes();
    for body in &dish::BODIES {
        for h in &handles {
            let p = dish::compose(body, Some(h));
            let m = Dish.generate(&p, Lod::Medium).expect("generate");
            let radial = |v: &glam::Vec3| v.x.hypot(v.z);
            // The profile on the side away from the handle (the −X column, in creation order,
            // pole to pole), and the outer wall radius at a height: the largest radius where
            // the profile polyline crosses that height.
            let column: Vec<glam::Vec3> = m
                .positions
                .iter()
                .zip(&m.body_vertices())
                .filter(|(v, body)| **body && v.x < 0.0 && v.z.abs() < 1e-6)
                .map(|(v, _)| *v)
                .collect();
            let wall_r = |y: f32| {
                column
                    .windows(2)
                    .filter(|w| (w[0].y - y) * (w[1].y - y) <= 0.0 && w[0].y != w[1].y)
                    .map(|w| {
                        let t = (y - w[0].y) / (w[1].y - w[0].y);
                        radial(&w[0]) + t * (radial(&w[1]) - radial(&w[0]))
                    })
                    .fold(0.0f32, f32::max)
            };
            for end in &m.positions[m.positions.len() - 2..] {
                assert!(
                    radial(end) < wall_r(end.y) - 0.001,
                    "{} + {}: end at {end} is outside the wall ({})",
                    body.name,
                    h.name,
                    wall_r(end.y)
                );
            }
        }
    }
}

#[test]
fn gradients_are_the_same_on_many_threads() {
    // The tape is thread-local: generators recorded at once on several threads (as the
    // optimiser's rayon population does) give exactly the single-threaded gradients.
    let presets = Dish.presets();
    let grad = |values: &[f64]| {
        let (m, vjp) = Dish.generate_with_vjp(values, Lod::Low).expect("vjp");
        let mut g = vec![0.0; values.len()];
        vjp.vjp(
            &vec![glam::Vec3::new(0.3, -0.2, 0.5); m.positions.len()],
            &mut g,
        )
        .expect("vjp");
        g
    };
    let serial: Vec<Vec<f64>> = presets.iter().map(|p| grad(&p.values)).collect();
    let parallel: Vec<Vec<f64>> = std::thread::scope(|s| {
        let handles: Vec<_> = presets
            .iter()
            .map(|p| {
                s.spawn(|| {
                    // Repeat so the threads' recordings overlap in time.
                    let mut g = Vec::new();
                    for _ in 0..5 {
                        g = grad(&p.values);
                    }
                    g
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("thread"))
            .collect()
    });
    assert_eq!(serial, parallel);
}

#[test]
fn mug_body_is_smooth_shaded_and_caps_are_flat() {
    // The body has no crease sharper than the crease limit at MEDIUM, so every body vertex
    // has one normal for all its corners; the handle's end caps are flat.
    let m = Dish
        .generate(&Dish.preset("mug").expect("mug").values, Lod::Medium)
        .expect("generate");
    let mut normal_of = vec![None; m.positions.len()];
    for (t, tri) in m.triangles.iter().enumerate() {
        for (k, &v) in tri.iter().enumerate() {
            let n = m.corner_normals[3 * t + k];
            if m.tri_parts[t] == 0 {
                match normal_of[v as usize] {
                    None => normal_of[v as usize] = Some(n),
                    Some(o) => assert!(n.dot(o) > 0.9999, "vertex {v}: {n} vs {o}"),
                }
            }
        }
    }
    // Cap triangles: every corner has the face normal.
    let mut flat = 0;
    for (t, tri) in m.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|i| m.positions[i as usize]);
        let face = (b - a).cross(c - a).normalize();
        if m.tri_parts[t] == 1 && (0..3).all(|k| m.corner_normals[3 * t + k].dot(face) > 0.9999) {
            flat += 1;
        }
    }
    assert!(flat >= 2 * 12, "only {flat} flat handle triangles");
}

#[test]
fn range_corners_give_valid_meshes() {
    check_range_corners(&Dish);
}

/// The tie-break prior: no preset's handle (round, ear, D, small) is pinched, a handle whose
/// middle is closer to the wall than its ends (what a turned round handle fitted side-on looks
/// like) is, by how much, and a handleless dish has no preference.
#[test]
fn tie_prior_marks_pinched_handles_only() {
    for p in Dish.presets() {
        let v = Dish.tie_prior(&p.values);
        assert!(v <= 0.01, "{}: {v}", p.name);
    }
    let mut x = Dish.preset("mug").unwrap().values;
    for k in 0..dish::HANDLE_STEPS {
        let s = k as f64 / (dish::HANDLE_STEPS - 1) as f64 - 0.5;
        // 0.3 at the ends, 0.2 in the middle.
        x[dish::P_SWEEP + k] = 0.2 + 0.4 * s * s;
    }
    let pinched = Dish.tie_prior(&x);
    assert!((0.07..0.1).contains(&pinched), "{pinched}");
    x[dish::P_HAS_HANDLE] = 0.0;
    assert_eq!(Dish.tie_prior(&x), 0.0);
}
