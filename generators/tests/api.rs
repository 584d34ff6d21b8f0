//! Contract tests over every registered generator: specs, presets and seeds are well formed,
//! and the differentiable path builds exactly the mesh of the plain path.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use procfit_generators::{Lod, all, by_name, sanitize_params};
use std::collections::HashSet;

#[test]
fn registry_lists_dish_and_building_by_name() {
    let names: Vec<&str> = all().iter().map(|g| g.name()).collect();
    assert_eq!(
        names.iter().collect::<HashSet<_>>().len(),
        names.len(),
        "{names:?}"
    );
    for n in ["dish", "building"] {
        assert!(names.contains(&n), "{n} is not registered");
        assert_eq!(by_name(n).map(|g| g.name()), Some(n));
    }
    assert!(by_name("teapot").is_none());
}

/// The tie-break prior is a finite, non-negative number on every preset and seed (0 for a
/// generator with no preference).
#[test]
fn tie_prior_is_finite_and_non_negative() {
    for g in all() {
        for (name, x) in g
            .presets()
            .into_iter()
            .map(|p| (p.name.to_owned(), p.values))
            .chain(g.seeds().into_iter().map(|s| ("seed".to_owned(), s)))
        {
            let v = g.tie_prior(&x);
            assert!(v.is_finite() && v >= 0.0, "{} {name}: {v}", g.name());
        }
    }
}

#[test]
fn specs_presets_and_seeds_are_well_formed() {
    for g in all() {
        let mut seen = HashSet::new();
        for s in g.params() {
            assert!(seen.insert(s.name), "{}: duplicate `{}`", g.name(), s.name);
            assert!(
                s.name
                    .chars()
                    .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_'),
                "{}: `{}` is not snake_case",
                g.name(),
                s.name
            );
            assert!(
                s.min < s.max && (s.min..=s.max).contains(&s.default),
                "{}",
                s.name
            );
            assert!(!s.label.is_empty() && !s.group.is_empty(), "{}", s.name);
        }
        let presets = g.presets();
        assert!(
            presets.len() >= 6,
            "{}: {} presets",
            g.name(),
            presets.len()
        );
        let mut names = HashSet::new();
        for p in &presets {
            assert!(
                names.insert(p.name),
                "{}: duplicate preset {}",
                g.name(),
                p.name
            );
            // Presets are already in range: sanitising changes nothing.
            assert_eq!(
                sanitize_params(g.params(), &p.values).as_ref(),
                Ok(&p.values),
                "{}",
                p.name
            );
        }
        for s in g.seeds() {
            assert_eq!(
                sanitize_params(g.params(), &s).as_ref(),
                Ok(&s),
                "{} seed",
                g.name()
            );
        }
    }
}

#[test]
fn dish_and_building_are_differentiable() {
    for n in ["dish", "building"] {
        assert!(by_name(n).is_some_and(|g| g.differentiable()), "{n}");
    }
}

#[test]
fn generate_with_vjp_builds_the_same_mesh_as_generate() {
    for g in all().into_iter().filter(|g| g.differentiable()) {
        for p in g.presets() {
            for lod in [Lod::Low, Lod::High] {
                let plain = g.generate(&p.values, lod).expect("generate");
                let (diff, _) = g
                    .generate_with_vjp(&p.values, lod)
                    .expect("generate_with_vjp");
                assert_eq!(plain, diff, "{} {} {lod:?}", g.name(), p.name);
            }
        }
    }
}

#[test]
fn capabilities_agree_with_what_each_generator_can_do() {
    use procfit_generators::{FitMethod, MaskExtra};
    let mut display = HashSet::new();
    for g in all() {
        let c = g.capabilities();
        assert!(
            !c.display_name.is_empty() && display.insert(c.display_name),
            "{}: empty or shared display name {:?}",
            g.name(),
            c.display_name
        );
        // A gradient fit needs the generator's vector–Jacobian product.
        if c.fit == Some(FitMethod::Gradients) {
            assert!(g.differentiable(), "{} is fitted by gradients", g.name());
            let p = g.defaults();
            assert!(g.generate_with_vjp(&p, Lod::Low).is_ok(), "{}", g.name());
        }
        // The tree GA reads branch/leaf labels and keeps a `seed` parameter on a refit.
        if c.fit == Some(FitMethod::TreeGa) {
            assert_eq!(c.mask_extra, MaskExtra::TreeLabels, "{}", g.name());
            assert!(g.params().iter().any(|p| p.name == "seed"), "{}", g.name());
        }
        if c.mask_extra == MaskExtra::TreeLabels {
            assert_eq!(c.fit, Some(FitMethod::TreeGa), "{}", g.name());
        }
        // Window labels are matched against the mesh's window parts.
        if c.mask_extra == MaskExtra::Windows {
            let mesh = g.generate(&g.defaults(), c.fitted_lod).expect("generate");
            assert!(
                mesh.parts.iter().any(|p| p.name.starts_with("window")),
                "{}: window labels but no window part at {:?}: {:?}",
                g.name(),
                c.fitted_lod,
                mesh.parts
            );
        }
    }
}
