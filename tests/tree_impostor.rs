//! Tree impostors through the silhouette renderer, and the tree fit that uses them: label images
//! hold both labels, similarity and IoU behave on rendered trees, the fit is consistent with
//! its own report and deterministic on any number of threads, and bad input is refused.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use procfit::generators::tree::{TreeGenerator, idx};
use procfit::generators::{Generator, Lod};
use procfit::mask::LabelImage;
use procfit::tree::ga::GaConfig;
use procfit::tree::impostor::{
    TreeFitConfig, TreeImpostor, fit_tree, frame_reference, silhouette_iou64, tree_view,
};
use procfit::tree::similarity::{SimilarityConfig, TreeReference, TreeTraits};
use procfit::tree::{BRANCH, LEAF, genome_to_params};

const SIZE: u32 = 96;

fn render(values: &[f64]) -> LabelImage {
    let view = tree_view(SIZE, SIZE, 12.0).expect("view");
    let mut imp = TreeImpostor::new(view).expect("impostor");
    let mesh = TreeGenerator.generate(values, Lod::Low).expect("tree");
    imp.render(&mesh).expect("renders")
}

fn preset(name: &str) -> Vec<f64> {
    TreeGenerator.preset(name).expect("preset").values
}

#[test]
fn impostors_hold_branches_and_leaves() {
    for name in ["oak", "birch", "willow", "poplar"] {
        let l = render(&preset(name));
        let count = |v: u8| l.labels().iter().filter(|&&x| x == v).count();
        assert!(count(LEAF) > 50, "{name}: {} leaf pixels", count(LEAF));
        assert!(
            count(BRANCH) > 20,
            "{name}: {} branch pixels",
            count(BRANCH)
        );
        // The foot of the trunk is at the bottom centre (tree_view frames the tree).
        let bottom_branch = (0..SIZE as usize)
            .rev()
            .find_map(|y| (0..SIZE as usize).find(|&x| l.labels()[y * SIZE as usize + x] == BRANCH))
            .expect("trunk");
        let centre = SIZE as usize / 2;
        assert!(
            bottom_branch.abs_diff(centre) < 8,
            "{name}: trunk at column {bottom_branch}"
        );
    }
}

#[test]
fn rendered_similarity_ranks_a_shrunk_tree_below_itself() {
    let oak = preset("oak");
    let r = TreeReference::new(
        &render(&oak),
        TreeTraits::default(),
        SimilarityConfig::default(),
    )
    .expect("oak is a tree");
    let itself = r
        .similarity(&render(&oak), &TreeTraits::default())
        .expect("sim");
    assert_eq!(itself, 1.0);
    let mut last = itself;
    for h in [11.0, 9.0, 6.0] {
        let mut v = oak.clone();
        v[idx::HEIGHT] = h;
        let s = r
            .similarity(&render(&v), &TreeTraits::default())
            .expect("sim");
        assert!(s < last && s > 0.0, "height {h}: {s} (previous {last})");
        last = s;
    }
}

#[test]
fn iou64_is_one_for_the_same_tree_and_lower_for_another() {
    let g = TreeGenerator;
    let a = g.generate(&preset("oak"), Lod::Low).expect("oak");
    let b = g.generate(&preset("poplar"), Lod::Low).expect("poplar");
    let same = silhouette_iou64(&a, &a, 32).expect("iou");
    let other = silhouette_iou64(&a, &b, 32).expect("iou");
    assert!((same - 1.0).abs() < 1e-12, "{same}");
    assert!(other < 0.6, "{other}");
    // The metric normalises each mesh to its bounding box: the same tree twice as large and
    // moved aside is the same tree.
    let mut moved = a.clone();
    for p in &mut moved.positions {
        *p = *p * 2.0 + glam::Vec3::new(3.0, 1.0, -2.0);
    }
    let moved_iou = silhouette_iou64(&a, &moved, 32).expect("iou");
    assert!(moved_iou > 0.99, "{moved_iou}");
    // Squashing it is not.
    let mut squashed = a.clone();
    for p in &mut squashed.positions {
        p.y *= 0.5;
    }
    let squashed_iou = silhouette_iou64(&a, &squashed, 32).expect("iou");
    assert!(squashed_iou < 0.8, "{squashed_iou}");
    assert!(silhouette_iou64(&a, &b, 0).is_err());
    let empty = procfit::generators::Mesh::default();
    assert!(silhouette_iou64(&a, &empty, 32).is_err());
}

#[test]
fn fit_reports_its_own_similarity_and_is_deterministic() {
    let view = tree_view(64, 64, 12.0).expect("view");
    let mut truth = preset("birch");
    truth[idx::SEED] = 5.0;
    truth[idx::HEIGHT] = 11.0;
    let reference = {
        let mut imp = TreeImpostor::new(view).expect("impostor");
        imp.render(&TreeGenerator.generate(&truth, Lod::Low).expect("tree"))
            .expect("renders")
    };
    let cfg = TreeFitConfig {
        ga: GaConfig {
            population: 8,
            generations: 3,
            levels: 2,
            seed: 3,
            ..GaConfig::default()
        },
        ..TreeFitConfig::default()
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| fit_tree(&reference, TreeTraits::default(), view, &cfg, None))
            .expect("fits")
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.params, b.params);
    assert_eq!(a.similarity, b.similarity);
    assert_eq!(a.ga.evaluations, cfg.evaluations());
    // The reported similarity is that of the returned parameters.
    let r = TreeReference::new(&reference, TreeTraits::default(), cfg.similarity).expect("tree");
    let mut imp = TreeImpostor::new(view).expect("impostor");
    let again = r
        .similarity(
            &imp.render(&TreeGenerator.generate(&a.params, Lod::Low).expect("tree"))
                .expect("renders"),
            &TreeTraits::default(),
        )
        .expect("sim");
    assert_eq!(again, a.similarity);
    assert_eq!(
        genome_to_params(TreeGenerator.params(), &a.ga.best.genome).expect("params"),
        a.params
    );
    assert!(a.similarity > 0.0);
}

#[test]
fn fit_refuses_bad_input() {
    let view = tree_view(64, 64, 12.0).expect("view");
    let cfg = TreeFitConfig::default();
    let wrong_size = LabelImage::new(32, 32, vec![LEAF; 32 * 32]).expect("labels");
    let err = fit_tree(&wrong_size, TreeTraits::default(), view, &cfg, None).expect_err("size");
    assert!(err.0.contains("32×32"), "{}", err.0);
    let leaves_only = LabelImage::new(64, 64, vec![LEAF; 64 * 64]).expect("labels");
    let err = fit_tree(&leaves_only, TreeTraits::default(), view, &cfg, None).expect_err("no wood");
    assert!(err.0.contains("no branch"), "{}", err.0);
    let graph = TreeFitConfig {
        use_graph_vertices: true,
        ..cfg
    };
    assert!(fit_tree(&render_64(), TreeTraits::default(), view, &graph, None).is_err());
    assert!(tree_view(64, 64, -1.0).is_err());
}

fn render_64() -> LabelImage {
    let view = tree_view(64, 64, 12.0).expect("view");
    let mut imp = TreeImpostor::new(view).expect("impostor");
    imp.render(
        &TreeGenerator
            .generate(&preset("oak"), Lod::Low)
            .expect("tree"),
    )
    .expect("renders")
}

#[test]
fn framing_puts_the_tree_where_the_camera_expects_it() {
    // A small tree in a corner of a wide image: a 3 px trunk and a leaf blob above it.
    let (w, h) = (200usize, 100usize);
    let mut px = vec![0u8; w * h];
    for y in 60..80 {
        for x in 29..32 {
            px[y * w + x] = BRANCH;
        }
    }
    for y in 40..60 {
        for x in 20..41 {
            px[y * w + x] = LEAF;
        }
    }
    let img = LabelImage::new(w as u32, h as u32, px).expect("labels");
    let f = frame_reference(&img, 100).expect("framed");
    let rows: Vec<usize> = (0..100)
        .filter(|&y| f.labels()[y * 100..(y + 1) * 100].iter().any(|&l| l != 0))
        .collect();
    assert_eq!((rows[0], rows[rows.len() - 1]), (10, 89), "tree rows");
    let foot: Vec<usize> = (0..100)
        .filter(|&x| f.labels()[89 * 100 + x] == BRANCH)
        .collect();
    let mid = (foot[0] + foot[foot.len() - 1] + 1) as f64 / 2.0;
    assert!((mid - 50.0).abs() <= 1.0, "foot centred at {mid}");
    let empty = LabelImage::new(4, 4, vec![0; 16]).expect("labels");
    assert!(frame_reference(&empty, 64).is_err());
    assert!(frame_reference(&img, 1).is_err());
}

#[test]
fn photo_camera_sees_the_trunk_plane_where_the_photo_has_it() {
    use procfit::tree::impostor::frame_reference_with;
    // A tree off to the left in a wide photo.
    let (w, h) = (300usize, 160usize);
    let mut px = vec![0u8; w * h];
    for y in 100..150 {
        for x in 58..62 {
            px[y * w + x] = BRANCH;
        }
    }
    for y in 30..100 {
        for x in 20..100 {
            px[y * w + x] = LEAF;
        }
    }
    let img = LabelImage::new(w as u32, h as u32, px).expect("labels");
    let (_, framing) = frame_reference_with(&img, 128).expect("framed");
    let fit_view = tree_view(128, 128, 12.0).expect("view");
    let photo = framing.photo_view().expect("camera");
    assert_eq!((photo.width, photo.height), (300, 160));
    for q in [
        glam::Vec3::new(0.0, 0.0, 0.0),
        glam::Vec3::new(3.0, 9.0, 0.0),
        glam::Vec3::new(-4.0, 5.0, 0.0),
    ] {
        let (r, _) = fit_view.project(q);
        let (p, _) = photo.project(q);
        // Reference pixel = 64 + (photo x − foot x)·scale, 0.9·128 + (photo y − foot y)·scale.
        let expect_x = 64.0 + (p.x - framing.foot.0) * framing.scale;
        let expect_y = 0.9 * 128.0 + (p.y - framing.foot.1) * framing.scale;
        assert!(
            (r.x - expect_x).abs() < 1e-6 && (r.y - expect_y).abs() < 1e-6,
            "{q}: reference {r}, from the photo ({expect_x}, {expect_y})"
        );
    }
}
