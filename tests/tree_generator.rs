//! Tree generator: every preset at every level of detail gives a valid, closed, outward-facing
//! mesh with all three parts, the same mesh for the same parameters, and bad input is refused.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use procfit::generators::tree::{self as tg, PART_BRANCH, PART_LEAF, PART_TRUNK, TreeGenerator};
use procfit::generators::{GenError, Generator, Lod, Mesh, by_name};
use std::collections::HashMap;

/// Signed volume of the triangles of one part (divergence theorem); positive when they enclose
/// space with outward-facing triangles.
fn signed_volume(m: &Mesh, part: u8) -> f64 {
    m.triangles
        .iter()
        .zip(&m.tri_parts)
        .filter(|&(_, &p)| p == part)
        .map(|(t, _)| {
            let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// Every directed edge must be matched by its reverse: the surface is closed and consistently
/// oriented (leaf cards count: their two sides pair up).
fn assert_closed(m: &Mesh, what: &str) {
    let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
    for t in &m.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_default() += if a < b { 1 } else { -1 };
        }
    }
    let open = edges.values().filter(|&&v| v != 0).count();
    assert_eq!(open, 0, "{what}: {open} edges without a reversed partner");
}

fn check(preset: &str, lod: Lod) {
    let g = TreeGenerator;
    let p = g.preset(preset).expect("preset exists");
    let what = format!("{preset} at {lod:?}");
    let m = g.generate(&p.values, lod).expect("generates");
    m.check().expect("valid mesh");
    let names: Vec<_> = m.parts.iter().map(|p| p.name).collect();
    assert_eq!(names, ["trunk", "branch", "leaf"], "{what}");
    for part in [PART_TRUNK, PART_BRANCH, PART_LEAF] {
        let n = m.tri_parts.iter().filter(|&&p| p == part).count();
        assert!(n > 0, "{what}: no triangles of part {part}");
    }
    assert_closed(&m, &what);
    // Tubes face outwards: positive enclosed volume. Leaf cards enclose nothing.
    assert!(
        signed_volume(&m, PART_TRUNK) > 0.0,
        "{what}: trunk inside out"
    );
    assert!(
        signed_volume(&m, PART_BRANCH) > 0.0,
        "{what}: branches inside out"
    );
    assert!(
        signed_volume(&m, PART_LEAF).abs() < 1e-6,
        "{what}: leaf cards not back to back"
    );
    // Leaf corner normals are the face normals (flat cards, each side its own normal).
    for (t, tri) in m.triangles.iter().enumerate() {
        if m.tri_parts[t] != PART_LEAF {
            continue;
        }
        let [a, b, c] = tri.map(|i| m.positions[i as usize]);
        let n = (b - a).cross(c - a).normalize_or_zero();
        for k in 0..3 {
            let d = n.dot(m.corner_normals[3 * t + k]);
            assert!(d > 0.99, "{what}: leaf triangle {t} normal off by dot {d}");
        }
    }
    // Stands on the ground, about as tall as asked.
    let (lo, hi) = m.bounds().expect("not empty");
    let height = p.values[tg::idx::HEIGHT] as f32;
    assert!(
        lo.y > -0.05 * height && lo.y < 0.01 * height,
        "{what}: base at {}",
        lo.y
    );
    assert!(
        hi.y > 0.5 * height && hi.y < 1.6 * height,
        "{what}: top {} for height {height}",
        hi.y
    );
    // The LOD caps on stems and leaves never cut a preset: same branch graph at every level.
    let stems = |l| tg::skeleton(&p.values, l).expect("skeleton").stems.len();
    assert_eq!(stems(lod), stems(Lod::Ultra), "{what}: stems capped");
    // Deterministic.
    assert_eq!(
        g.generate(&p.values, lod).expect("generates"),
        m,
        "{what}: not deterministic"
    );
}

#[test]
fn presets_are_valid_at_every_lod() {
    let presets = TreeGenerator.presets();
    assert!(presets.len() >= 6);
    for p in &presets {
        for lod in Lod::ALL {
            check(p.name, lod);
        }
    }
}

#[test]
fn registered_and_not_differentiable() {
    let g = by_name("tree").expect("registered in all()");
    assert!(!g.differentiable());
    let d = g.defaults();
    assert!(matches!(
        g.generate_with_vjp(&d, Lod::Low),
        Err(GenError::NotDifferentiable(_))
    ));
}

#[test]
fn seed_changes_the_tree() {
    let g = TreeGenerator;
    let mut a = g.preset("oak").expect("oak").values;
    let m1 = g.generate(&a, Lod::Low).expect("oak");
    a[tg::idx::SEED] += 1.0;
    let m2 = g.generate(&a, Lod::Low).expect("oak, other seed");
    assert_ne!(m1.positions, m2.positions, "seed has no effect");
}

/// Silhouette descriptors of a preset: height over width, and the height of the lowest and of
/// the widest-reaching leaf as fractions of the tree height.
fn descriptors(m: &Mesh) -> [f32; 3] {
    let (lo, hi) = m.bounds().expect("not empty");
    let e = hi - lo;
    let leaf_points = m
        .triangles
        .iter()
        .zip(&m.tri_parts)
        .filter(|&(_, &p)| p == PART_LEAF)
        .flat_map(|(t, _)| t.map(|i| m.positions[i as usize]));
    let (mut lowest, mut widest, mut reach) = (f32::MAX, 0.0, 0.0);
    for p in leaf_points {
        lowest = lowest.min(p.y);
        let r = p.x.hypot(p.z);
        if r > reach {
            reach = r;
            widest = p.y;
        }
    }
    [
        e.y / e.x.max(e.z),
        (lowest - lo.y) / e.y,
        (widest - lo.y) / e.y,
    ]
}

#[test]
fn presets_differ_in_silhouette() {
    // Species must not collapse onto one shape: every pair differs by more than 10 % in
    // proportions or by more than 0.08 of the height in where the leaves are.
    let g = TreeGenerator;
    let d: Vec<(&str, [f32; 3])> = g
        .presets()
        .iter()
        .map(|p| {
            (
                p.name,
                descriptors(&g.generate(&p.values, Lod::Low).expect("gen")),
            )
        })
        .collect();
    for (i, a) in d.iter().enumerate() {
        for b in &d[i + 1..] {
            let aspect = a.1[0].max(b.1[0]) / a.1[0].min(b.1[0]) > 1.1;
            let leaves = (a.1[1] - b.1[1]).abs() > 0.08 || (a.1[2] - b.1[2]).abs() > 0.08;
            assert!(aspect || leaves, "{} and {} look alike: {d:?}", a.0, b.0);
        }
    }
}

#[test]
fn random_parameter_vectors_give_valid_meshes() {
    // The GA samples the whole box: corners included.
    let g = TreeGenerator;
    let spec = g.params();
    let mut s = 0x1234_5678_u64;
    for k in 0..40 {
        let v: Vec<f64> = spec
            .iter()
            .map(|p| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let u = (s >> 11) as f64 / (1u64 << 53) as f64;
                match k % 4 {
                    0 => p.min,
                    1 => p.max,
                    _ => p.min + u * (p.max - p.min),
                }
            })
            .collect();
        let m = g.generate(&v, Lod::Low).expect("random tree");
        m.check().expect("valid");
        assert_closed(&m, &format!("random tree {k}"));
    }
}

#[test]
fn bad_parameters_are_refused() {
    let g = TreeGenerator;
    let mut v = g.defaults();
    assert!(matches!(
        g.generate(&v[1..], Lod::Low),
        Err(GenError::WrongLength { .. })
    ));
    v[tg::idx::HEIGHT] = f64::NAN;
    assert!(matches!(
        g.generate(&v, Lod::Low),
        Err(GenError::NotFinite { name: "height" })
    ));
    assert!(tg::skeleton(&[0.0; 3], Lod::Low).is_err());
}

#[test]
fn skeleton_counts_graph_vertices() {
    let g = TreeGenerator;
    let p = g.preset("pine").expect("pine").values;
    let sk = tg::skeleton(&p, Lod::Low).expect("skeleton");
    let expected: usize = sk.stems.iter().map(|s| s.points.len()).sum();
    assert_eq!(sk.graph_vertices(), expected);
    assert!(sk.stems.len() > 10 && !sk.leaves.is_empty());
}

/// Bounding box of the leaf triangles (the crown) of a mesh.
fn crown_box(m: &Mesh) -> (glam::Vec3, glam::Vec3) {
    let mut lo = glam::Vec3::INFINITY;
    let mut hi = glam::Vec3::NEG_INFINITY;
    for (t, &p) in m.triangles.iter().zip(&m.tri_parts) {
        if p == PART_LEAF {
            for &i in t {
                lo = lo.min(m.positions[i as usize]);
                hi = hi.max(m.positions[i as usize]);
            }
        }
    }
    (lo, hi)
}

/// Issue 17: LOD 0 (what the fit matches to the photo) merges leaves into larger cards, and its
/// crown used to be 5–12 % taller and 4–14 % wider than the finer levels' (what is exported).
/// The finer levels' crown box must now be within 2 % of LOD 0's on every side, for every preset
/// and several seeds, and LOD 0 itself is left as the GA has always seen it.
#[test]
fn crown_size_does_not_change_with_the_level_of_detail() {
    let g = TreeGenerator;
    let mut worst = 0.0f32;
    for preset in g.presets() {
        for seed in [0.0, 7.0, 123.0] {
            let mut values = preset.values.clone();
            values[tg::idx::SEED] = seed;
            let (lo0, hi0) = crown_box(&g.generate(&values, Lod::Low).unwrap());
            let size = hi0 - lo0;
            for lod in [Lod::Medium, Lod::High, Lod::Ultra] {
                let (lo, hi) = crown_box(&g.generate(&values, lod).unwrap());
                let off = ((lo - lo0).abs().max((hi - hi0).abs()) / size).max_element();
                worst = worst.max(off);
                assert!(
                    off <= 0.02,
                    "{} seed {seed} lod {}: crown box {lo}..{hi}, at lod 0 {lo0}..{hi0} ({:.1} % off)",
                    preset.name,
                    lod.index(),
                    100.0 * off
                );
            }
        }
    }
    println!(
        "worst crown box difference from lod 0: {:.2} %",
        100.0 * worst
    );
}
