//! Shared by `tests/tree_recovery.rs` and `benches/tree.rs`: the three non-preset trees the
//! recovery test asserts on and the bench reports.

use procfit::generators::Generator;
use procfit::generators::tree::{TreeGenerator, idx};

/// Three trees that are not presets: presets with another seed and changed proportions.
pub fn targets() -> Vec<(&'static str, Vec<f64>)> {
    let g = TreeGenerator;
    let p = |n: &str| g.preset(n).expect("preset").values;
    let mut a = p("oak");
    a[idx::SEED] = 77.0;
    a[idx::HEIGHT] = 10.0;
    a[idx::SHAPE] = 1.0;
    a[idx::SPLITS] = 1.0;
    let mut b = p("birch");
    b[idx::SEED] = 12.0;
    b[idx::HEIGHT] = 13.0;
    b[idx::LEVEL0 + 1] = 0.4;
    b[idx::TROPISM] = 0.0;
    let mut c = p("willow");
    c[idx::SEED] = 301.0;
    c[idx::HEIGHT] = 11.0;
    c[idx::TROPISM] = -0.6;
    c[idx::BASE_SIZE] = 0.35;
    vec![("oak-like", a), ("birch-like", b), ("willow-like", c)]
}
