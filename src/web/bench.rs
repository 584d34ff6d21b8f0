//! Benchmark workloads for the wasm bench page (`bench.html`, `scripts/bench-wasm.mjs`): the very
//! workloads the native benches time, behind opaque handles. Timing happens in JS
//! (`performance.now()` in the worker); each method here is one timed step.

use super::js;
use crate::generators::{self, Lod};
use crate::render::bench::{BenchMesh, BenchScene};
use crate::segment::bench::synthetic_photo_jpeg;
use crate::segment::{Label, Options, Photo, Session, Stroke, WORKING_SIDE};
use glam::Vec3;
use wasm_bindgen::prelude::*;

/// The renderer benchmark scene of `benches/render.rs`.
#[wasm_bindgen]
pub struct RenderBench {
    scene: BenchScene,
}

#[wasm_bindgen]
impl RenderBench {
    /// `large`: the ~20k-vertex cup instead of the ~3.8k one; `size`: image side; `views`.
    #[wasm_bindgen(constructor)]
    pub fn new(large: bool, size: u32, views: u32) -> Result<RenderBench, JsError> {
        let mesh = if large {
            BenchMesh::Large
        } else {
            BenchMesh::Small
        };
        let scene = BenchScene::new(mesh, size, views as usize).map_err(js)?;
        Ok(RenderBench { scene })
    }

    /// Vertex count of the mesh.
    #[wasm_bindgen(js_name = vertexCount)]
    pub fn vertex_count(&self) -> u32 {
        self.scene.n_vertices() as u32
    }

    /// Run views on the rayon pool (or not).
    #[wasm_bindgen(js_name = setParallel)]
    pub fn set_parallel(&mut self, parallel: bool) {
        self.scene.set_parallel(parallel);
    }

    /// One forward render of the first view.
    pub fn forward(&mut self) -> Result<(), JsError> {
        self.scene.forward().map_err(js)
    }

    /// One forward + backward of the first view.
    #[wasm_bindgen(js_name = forwardBackward)]
    pub fn forward_backward(&mut self) -> Result<f64, JsError> {
        self.scene.forward_backward().map_err(js)
    }

    /// The multi-view loss and gradient over all views.
    pub fn evaluate(&mut self) -> Result<f64, JsError> {
        self.scene.evaluate().map_err(js)
    }
}

/// The segmentation benchmark of `benches/segment.rs`: a 12 MP JPEG → working-resolution mask.
#[wasm_bindgen]
pub struct SegmentBench {
    jpeg: Vec<u8>,
    photo: Option<Photo>,
    session: Option<Session>,
    strokes: u32,
}

#[wasm_bindgen]
impl SegmentBench {
    /// Makes the synthetic 12 MP JPEG (slow: not part of any timing).
    #[wasm_bindgen(constructor)]
    pub fn new() -> SegmentBench {
        SegmentBench {
            jpeg: synthetic_photo_jpeg(),
            photo: None,
            session: None,
            strokes: 0,
        }
    }

    /// Size of the JPEG in bytes.
    #[wasm_bindgen(js_name = jpegBytes)]
    pub fn jpeg_bytes(&self) -> u32 {
        self.jpeg.len() as u32
    }

    /// Decode + EXIF + downscale to the working resolution.
    pub fn decode(&mut self) -> Result<(), JsError> {
        self.photo = Some(Photo::decode(&self.jpeg, WORKING_SIDE).map_err(js)?);
        Ok(())
    }

    /// The automatic mask of the decoded photo.
    pub fn automatic(&mut self) -> Result<(), JsError> {
        let photo = self
            .photo
            .as_ref()
            .ok_or_else(|| JsError::new("decode first"))?;
        self.session = Some(Session::automatic(photo, &Options::default()).map_err(js)?);
        Ok(())
    }

    /// Adds a scribble (alternately background and object) and re-cuts.
    pub fn recut(&mut self) -> Result<(), JsError> {
        let session = self
            .session
            .as_mut()
            .ok_or_else(|| JsError::new("segment first"))?;
        self.strokes += 1;
        let stroke = if self.strokes % 2 == 1 {
            Stroke {
                label: Label::Background,
                points: vec![[20.0, 300.0], [120.0, 320.0]],
                radius: 4.0,
            }
        } else {
            Stroke {
                label: Label::Object,
                points: vec![[330.0, 200.0], [340.0, 230.0]],
                radius: 3.0,
            }
        };
        session.add_stroke(&stroke).map_err(js)?;
        session.recut().map_err(js)?;
        Ok(())
    }
}

impl Default for SegmentBench {
    fn default() -> Self {
        Self::new()
    }
}

/// A generator at one preset and LOD: `generate` and the gradient (tape + VJP).
#[wasm_bindgen]
pub struct GeneratorBench {
    generator: &'static dyn generators::Generator,
    params: Vec<f64>,
    lod: Lod,
    adjoint: Vec<Vec3>,
    grad: Vec<f64>,
}

#[wasm_bindgen]
impl GeneratorBench {
    /// A bench for `generator`'s `preset` at `lod` (0..=3).
    #[wasm_bindgen(constructor)]
    pub fn new(generator: &str, preset: &str, lod: u32) -> Result<GeneratorBench, JsError> {
        let g = generators::by_name(generator)
            .ok_or_else(|| JsError::new(&format!("unknown generator {generator}")))?;
        let p = g
            .preset(preset)
            .ok_or_else(|| JsError::new(&format!("no preset {preset}")))?;
        let lod = Lod::from_index(lod as usize).ok_or_else(|| JsError::new("lod is 0..=3"))?;
        let n = g.generate(&p.values, lod).map_err(js)?.positions.len();
        // A fixed, non-trivial adjoint so the VJP does real work.
        let adjoint = (0..n)
            .map(|i| Vec3::new(1.0, (i % 7) as f32 * 0.1, -0.5))
            .collect();
        Ok(GeneratorBench {
            generator: g,
            grad: vec![0.0; p.values.len()],
            params: p.values,
            lod,
            adjoint,
        })
    }

    /// Vertex count of the mesh.
    #[wasm_bindgen(js_name = vertexCount)]
    pub fn vertex_count(&self) -> u32 {
        self.adjoint.len() as u32
    }

    /// One `generate`.
    pub fn generate(&self) -> Result<u32, JsError> {
        Ok(self
            .generator
            .generate(&self.params, self.lod)
            .map_err(js)?
            .triangles
            .len() as u32)
    }

    /// One `generate_with_vjp` + `vjp`.
    pub fn gradient(&mut self) -> Result<f64, JsError> {
        let (_, vjp) = self
            .generator
            .generate_with_vjp(&self.params, self.lod)
            .map_err(js)?;
        self.grad.fill(0.0);
        vjp.vjp(&self.adjoint, &mut self.grad).map_err(js)?;
        Ok(self.grad.iter().sum())
    }
}
