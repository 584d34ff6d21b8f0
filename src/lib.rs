//! procfit's core: photo → mask → fit (generator → silhouette raster → loss → optimiser) →
//! mesh → GLB, as plain Rust with no JavaScript in sight.
//!
//! Data flows one way through these modules (see ARCHITECTURE.md for the codemap):
//! [`segment`] turns a photo into a mask; [`reconstruct`] fits a generator from
//! `procfit_generators` to the masks by rendering silhouettes with [`render`] through a
//! [`camera`], scoring them with [`loss`] and stepping the parameters with [`optim`] (trees use
//! [`tree`]); [`colors`] gives its parts the photos' colours; [`glb`] writes the result. [`model`] is the params JSON shared by the CLI, the
//! page and the GLB extras. Only `web` (compiled for wasm32 alone) talks to JavaScript.

pub use procfit_generators as generators;

pub mod bench_cases;
pub mod building_bench;
pub mod camera;
pub mod colors;
pub mod dish_photo_bench;
pub mod export;
pub mod glb;
pub mod loss;
pub mod mask;
pub mod model;
pub mod optim;
pub mod reconstruct;
pub mod render;
pub mod segment;
pub mod tree;

#[cfg(target_arch = "wasm32")]
pub mod web;

/// The crate version, as shown by the CLI and the page.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
