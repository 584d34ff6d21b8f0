//! Tree similarity (paper eq. 3) on synthetic label images: 1 for identical masks, symmetric,
//! strictly lower and falling further as the reference is shifted, scaled or thinned; masks
//! that cannot guide a fit are refused with a clear message.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use procfit::mask::LabelImage;
use procfit::tree::similarity::{SimilarityConfig, TreeReference, TreeTraits, compare, profile};
use procfit::tree::{BACKGROUND, BRANCH, LEAF};

const W: u32 = 128;
const H: u32 = 128;

/// A synthetic tree: a trunk from the ground (row `ground`) up into an elliptic crown of leaves
/// with the trunk showing through its lower part. `scale` grows it about its foot, `dx`/`dy`
/// move it, and every `thin`-th crown pixel (0 = none) is cleared.
#[derive(Clone, Copy)]
struct Tree {
    dx: f64,
    dy: f64,
    scale: f64,
    thin: usize,
}

const BASE: Tree = Tree {
    dx: 0.0,
    dy: 0.0,
    scale: 1.0,
    thin: 0,
};

fn draw(t: Tree) -> LabelImage {
    let foot = (64.0 + t.dx, 118.0 + t.dy);
    let s = t.scale;
    let mut px = vec![BACKGROUND; (W * H) as usize];
    for y in 0..H as usize {
        for x in 0..W as usize {
            let (fx, fy) = (x as f64 + 0.5, y as f64 + 0.5);
            // Coordinates relative to the foot, in unscaled units (up is positive).
            let (u, v) = ((fx - foot.0) / s, (foot.1 - fy) / s);
            let crown = ((u - 2.0) / 34.0).powi(2) + ((v - 62.0) / 36.0).powi(2) <= 1.0;
            let trunk = u.abs() <= 3.5 && (0.0..=70.0).contains(&v);
            let i = y * W as usize + x;
            if trunk && v < 45.0 {
                px[i] = BRANCH;
            } else if crown {
                let keep = t.thin == 0 || (x * 7 + y * 13) % t.thin != 0;
                px[i] = if !keep {
                    BACKGROUND
                } else if trunk {
                    BRANCH
                } else {
                    LEAF
                };
            }
        }
    }
    LabelImage::new(W, H, px).expect("valid size")
}

fn sim(reference: Tree, candidate: Tree) -> f64 {
    let r = TreeReference::new(
        &draw(reference),
        TreeTraits::default(),
        SimilarityConfig::default(),
    )
    .expect("reference is a tree");
    r.similarity(&draw(candidate), &TreeTraits::default())
        .expect("same size")
}

/// Similarity must fall strictly, step after step, along a sequence of candidates.
fn check_falls(what: &str, steps: &[Tree]) {
    let mut last = sim(BASE, BASE);
    assert!((last - 1.0).abs() < 1e-12, "identical masks score {last}");
    for (k, &t) in steps.iter().enumerate() {
        let s = sim(BASE, t);
        assert!(s < last, "{what}: step {k} scores {s}, not below {last}");
        assert!(s > 0.0, "{what}: step {k} scores 0");
        last = s;
    }
}

#[test]
fn identical_masks_score_one() {
    assert_eq!(sim(BASE, BASE), 1.0);
    let other = Tree {
        scale: 0.8,
        dx: -5.0,
        ..BASE
    };
    assert_eq!(sim(other, other), 1.0);
}

#[test]
fn shifting_lowers_similarity() {
    let sh = |dx, dy| Tree { dx, dy, ..BASE };
    check_falls(
        "right",
        &[sh(1.0, 0.0), sh(3.0, 0.0), sh(6.0, 0.0), sh(12.0, 0.0)],
    );
    check_falls(
        "left",
        &[sh(-1.0, 0.0), sh(-3.0, 0.0), sh(-6.0, 0.0), sh(-12.0, 0.0)],
    );
    check_falls("down", &[sh(0.0, 2.0), sh(0.0, 4.0), sh(0.0, 8.0)]);
}

#[test]
fn scaling_lowers_similarity() {
    let sc = |scale| Tree { scale, ..BASE };
    check_falls("smaller", &[sc(0.95), sc(0.85), sc(0.7), sc(0.5)]);
    check_falls("larger", &[sc(1.03), sc(1.06), sc(1.1)]);
}

#[test]
fn thinning_lowers_similarity() {
    let th = |thin| Tree { thin, ..BASE };
    check_falls("thinned crown", &[th(11), th(5), th(3), th(2)]);
}

#[test]
fn similarity_is_symmetric() {
    let cases = [
        Tree { dx: 5.0, ..BASE },
        Tree { scale: 0.8, ..BASE },
        Tree { thin: 3, ..BASE },
        Tree {
            dx: -3.0,
            dy: 2.0,
            scale: 0.9,
            thin: 4,
        },
    ];
    let cfg = SimilarityConfig::default();
    let traits = TreeTraits {
        leaf_size: Some(2.0),
        graph_vertices: Some(300.0),
    };
    let other = TreeTraits {
        leaf_size: Some(3.0),
        graph_vertices: Some(200.0),
    };
    for t in cases {
        let a = profile(&draw(BASE), &cfg).expect("tree");
        let b = profile(&draw(t), &cfg).expect("tree");
        let ab = compare(&a, &traits, &b, &other, &cfg).value;
        let ba = compare(&b, &other, &a, &traits, &cfg).value;
        assert!((ab - ba).abs() < 1e-12, "{ab} vs {ba}");
        assert!(ab > 0.0 && ab < 1.0);
    }
}

#[test]
fn traits_multiply_in_as_min_over_max() {
    let cfg = SimilarityConfig::default();
    let r = TreeReference::new(
        &draw(BASE),
        TreeTraits {
            leaf_size: Some(2.0),
            graph_vertices: Some(400.0),
        },
        cfg,
    )
    .expect("tree");
    let c = TreeTraits {
        leaf_size: Some(3.0),
        graph_vertices: Some(100.0),
    };
    let s = r.similarity(&draw(BASE), &c).expect("same size");
    assert!((s - (2.0 / 3.0) * (100.0 / 400.0)).abs() < 1e-12, "{s}");
    // A side without the trait leaves the factor out.
    let s = r
        .similarity(&draw(BASE), &TreeTraits::default())
        .expect("same size");
    assert_eq!(s, 1.0);
}

#[test]
fn stripes_follow_the_paper() {
    let cfg = SimilarityConfig::default();
    let p = profile(&draw(BASE), &cfg).expect("tree");
    assert_eq!(p.stripes.len(), 24);
    // The bottom stripe is bare trunk (7 px wide), the middle of the crown is dense leaves.
    let bottom = p.stripes.last().expect("stripes");
    assert!(bottom.is_trunk(cfg.trunk_ratio));
    let (a, d) = bottom.crown.expect("trunk present");
    assert_eq!(d - a, 8.0);
    let mid = &p.stripes[6];
    assert!(!mid.is_trunk(cfg.trunk_ratio));
    let (a, d) = mid.crown.expect("crown present");
    let (b, c) = mid.dense.expect("dense crown");
    assert!(a <= b && b < c && c <= d, "[{a}, {b}, {c}, {d}]");
    assert!(c - b > 0.5 * (d - a));
}

fn refused(labels: Vec<u8>, message: &str) {
    let img = LabelImage::new(4, 4, labels).expect("valid size");
    let err = TreeReference::new(&img, TreeTraits::default(), SimilarityConfig::default())
        .expect_err("must be refused");
    assert!(err.0.contains(message), "`{}` lacks `{message}`", err.0);
}

#[test]
fn masks_without_leaves_branches_or_anything_are_refused() {
    refused(vec![BACKGROUND; 16], "no tree");
    refused([vec![BRANCH; 4], vec![BACKGROUND; 12]].concat(), "no leaf");
    refused([vec![LEAF; 4], vec![BACKGROUND; 12]].concat(), "no branch");
    refused(vec![LabelImage::DONT_CARE; 16], "no tree");
}

#[test]
fn bad_settings_and_candidates_are_refused() {
    let img = draw(BASE);
    for stripes in [0, 100_000] {
        let cfg = SimilarityConfig {
            stripes,
            ..SimilarityConfig::default()
        };
        assert!(TreeReference::new(&img, TreeTraits::default(), cfg).is_err());
    }
    let bad = TreeTraits {
        leaf_size: Some(f64::NAN),
        graph_vertices: None,
    };
    assert!(TreeReference::new(&img, bad, SimilarityConfig::default()).is_err());
    let r =
        TreeReference::new(&img, TreeTraits::default(), SimilarityConfig::default()).expect("tree");
    let small = LabelImage::new(4, 4, vec![LEAF; 16]).expect("valid");
    assert!(r.similarity(&small, &TreeTraits::default()).is_err());
    // An empty candidate is a valid but worthless tree.
    let empty = LabelImage::new(W, H, vec![BACKGROUND; (W * H) as usize]).expect("valid");
    assert_eq!(r.similarity(&empty, &TreeTraits::default()), Ok(0.0));
}
