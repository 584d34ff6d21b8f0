//! Shared helpers of the GLB tests: a tiny test generator (a prism with a glass lid and a leaf
//! card, hard edges and a UV seam, so vertex splitting and every material look are exercised),
//! a seeded random source, and tools to take a GLB apart and put an edited one back together.

#![allow(dead_code, reason = "each test binary uses a different subset")]

use glam::{Vec2, Vec3};
use procfit::generators::{
    GenError, Generator, Lod, Mesh, ParamKind, ParamSpec, Part, Preset, sanitize_params,
};
use procfit::model::ParamsDoc;

/// A prism of `sides` flat walls with a bottom cap (`body`), an optional glass lid
/// (`window_glass`), an optional leaf card (`leaves`) and a part that never has triangles
/// (`unused`). The level of detail multiplies the number of sides.
pub struct Prism;

const PRISM_PARAMS: &[ParamSpec] = &[
    spec("radius", 0.05, 1.0, 0.3, ParamKind::Continuous),
    spec("height", 0.05, 2.0, 0.5, ParamKind::Continuous),
    spec("sides", 3.0, 24.0, 6.0, ParamKind::Integer),
    spec("glass_lid", 0.0, 1.0, 1.0, ParamKind::Boolean),
    spec("leaf", 0.0, 1.0, 1.0, ParamKind::Boolean),
];

const fn spec(name: &'static str, min: f64, max: f64, default: f64, kind: ParamKind) -> ParamSpec {
    ParamSpec {
        name,
        label: name,
        group: "Test",
        unit: "",
        min,
        max,
        default,
        kind,
    }
}

impl Generator for Prism {
    fn name(&self) -> &'static str {
        "test_prism"
    }
    fn label(&self) -> &'static str {
        "Test prism"
    }
    fn version(&self) -> u32 {
        3
    }
    fn params(&self) -> &[ParamSpec] {
        PRISM_PARAMS
    }
    fn presets(&self) -> Vec<Preset> {
        vec![
            Preset {
                name: "lantern",
                label: "Lantern",
                values: vec![0.3, 0.5, 6.0, 1.0, 1.0],
            },
            Preset {
                name: "plain",
                label: "Plain",
                values: vec![0.8, 0.2, 3.0, 0.0, 0.0],
            },
        ]
    }
    fn differentiable(&self) -> bool {
        false
    }
    fn capabilities(&self) -> procfit::generators::Capabilities {
        procfit::generators::Capabilities {
            fit: None,
            display_name: "Test prism",
            fitted_lod: Lod::Low,
            mask_extra: procfit::generators::MaskExtra::None,
            fit_runs: 1,
            photo_match_level: 0.85,
            outline_smoothing: 0.5,
            free_depth: false,
        }
    }
    fn generate(&self, params: &[f64], lod: Lod) -> Result<Mesh, GenError> {
        let p = sanitize_params(self.params(), params)?;
        let (radius, height) = (p[0] as f32, p[1] as f32);
        let sides = p[2] as usize * (1 + lod.index());
        let mut m = Mesh {
            parts: vec![
                Part {
                    name: "body",
                    color: [0.8, 0.3, 0.2, 1.0],
                },
                Part {
                    name: "window_glass",
                    color: [0.6, 0.8, 0.9, 1.0],
                },
                Part {
                    name: "leaves",
                    color: [0.2, 0.6, 0.1, 1.0],
                },
                Part {
                    name: "unused",
                    color: [1.0, 1.0, 1.0, 1.0],
                },
            ],
            ..Mesh::default()
        };
        let angle = |i: usize| std::f32::consts::TAU * (i % sides) as f32 / sides as f32;
        for y in [0.0, height] {
            for i in 0..sides {
                let a = angle(i);
                m.positions
                    .push(Vec3::new(radius * a.cos(), y, -radius * a.sin()));
            }
        }
        let (bottom, top) = (m.positions.len() as u32, m.positions.len() as u32 + 1);
        m.positions.push(Vec3::ZERO);
        m.positions.push(Vec3::new(0.0, height, 0.0));
        let s = sides as u32;
        let tri = |m: &mut Mesh, t: [u32; 3], n: [Vec3; 3], uv: [Vec2; 3], part: u8| {
            m.triangles.push(t);
            m.corner_normals.extend(n);
            m.corner_uvs.extend(uv);
            m.tri_parts.push(part);
        };
        for i in 0..s {
            let j = (i + 1) % s;
            // Flat wall normals: hard edges between walls. u runs 0..1 round the prism, so the
            // last wall ends at u = 1 on vertex 0, which starts at u = 0: a UV seam.
            let mid = 0.5 * (angle(i as usize) + angle(i as usize + 1));
            let n = Vec3::new(mid.cos(), 0.0, -mid.sin());
            let (u0, u1) = (i as f32 / s as f32, (i + 1) as f32 / s as f32);
            let (b0, b1, t0, t1) = (i, j, i + s, j + s);
            tri(
                &mut m,
                [b0, b1, t1],
                [n; 3],
                [Vec2::new(u0, 1.0), Vec2::new(u1, 1.0), Vec2::new(u1, 0.0)],
                0,
            );
            tri(
                &mut m,
                [b0, t1, t0],
                [n; 3],
                [Vec2::new(u0, 1.0), Vec2::new(u1, 0.0), Vec2::new(u0, 0.0)],
                0,
            );
            tri(
                &mut m,
                [bottom, b1, b0],
                [Vec3::NEG_Y; 3],
                [Vec2::ZERO; 3],
                0,
            );
            let lid = if p[3] > 0.5 { 1 } else { 0 };
            tri(&mut m, [top, t0, t1], [Vec3::Y; 3], [Vec2::ONE; 3], lid);
        }
        if p[4] > 0.5 {
            let base = m.positions.len() as u32;
            let (y0, y1) = (height * 1.1, height * 1.3);
            m.positions.extend([
                Vec3::new(-0.1, y0, 0.0),
                Vec3::new(0.1, y0, 0.0),
                Vec3::new(0.1, y1, 0.0),
                Vec3::new(-0.1, y1, 0.0),
            ]);
            let uv = [
                Vec2::new(0.0, 1.0),
                Vec2::ONE,
                Vec2::new(1.0, 0.0),
                Vec2::ZERO,
            ];
            tri(
                &mut m,
                [base, base + 1, base + 2],
                [Vec3::Z; 3],
                [uv[0], uv[1], uv[2]],
                2,
            );
            tri(
                &mut m,
                [base, base + 2, base + 3],
                [Vec3::Z; 3],
                [uv[0], uv[2], uv[3]],
                2,
            );
        }
        m.check()?;
        Ok(m)
    }
}

/// A zig-zag strip of `n` vertices whose corners all agree, so the exporter writes exactly `n`.
pub fn strip(n: usize) -> Mesh {
    let positions: Vec<Vec3> = (0..n)
        .map(|i| Vec3::new((i / 2) as f32 * 0.01, (i % 2) as f32, 0.0))
        .collect();
    let mut m = Mesh {
        positions,
        parts: vec![Part {
            name: "strip",
            color: [1.0; 4],
        }],
        ..Mesh::default()
    };
    for i in 0..n as u32 - 2 {
        let t = if i % 2 == 0 {
            [i, i + 1, i + 2]
        } else {
            [i + 1, i, i + 2]
        };
        m.triangles.push(t);
        m.tri_parts.push(0);
        for k in t {
            m.corner_normals.push(Vec3::Z);
            m.corner_uvs.push(Vec2::new(k as f32, 0.0));
        }
    }
    m
}

/// The params document of `g` with these values, lod and seed (what `Model::to_doc` writes).
pub fn doc_of(g: &dyn Generator, values: &[f64], lod: Lod, seed: Option<u64>) -> ParamsDoc {
    ParamsDoc {
        generator: g.name().to_string(),
        version: g.version(),
        params: g
            .params()
            .iter()
            .zip(values)
            .map(|(s, &v)| (s.name.to_string(), serde_json::Value::from(v)))
            .collect(),
        lod: Some(lod as u8),
        seed,
        colors: Default::default(),
    }
}

/// xorshift64*: a tiny seeded random source, so failures reproduce.
pub struct Rng(pub u64);

impl Rng {
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    /// Uniform in `0..n` (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
    /// Uniform in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The JSON chunk (parsed) and the BIN chunk of a well-formed GLB.
pub fn take_apart(glb: &[u8]) -> (serde_json::Value, Vec<u8>) {
    let word = |at: usize| u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
    let json_len = word(12);
    let json: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let bin_at = 20 + json_len;
    let bin = if glb.len() > bin_at {
        let len = word(bin_at);
        glb[bin_at + 8..bin_at + 8 + len].to_vec()
    } else {
        Vec::new()
    };
    (json, bin)
}

/// A GLB with these JSON bytes and BIN chunk, framed correctly (lengths and padding).
pub fn frame(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let mut json = json.to_vec();
    json.resize(json.len().next_multiple_of(4), b' ');
    let mut bin = bin.to_vec();
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + json.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
    }
    out
}

/// `glb` with its JSON edited by `edit`.
pub fn edit_json(glb: &[u8], edit: impl FnOnce(&mut serde_json::Value)) -> Vec<u8> {
    let (mut json, bin) = take_apart(glb);
    edit(&mut json);
    frame(&serde_json::to_vec(&json).unwrap(), &bin)
}
