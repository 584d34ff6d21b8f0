//! A mesh under construction, generic over the scalar type, and the shared glue that turns a
//! generator written once over [`Scalar`] into `generate` (plain `f64`) and
//! `generate_with_vjp` (recorded on the tape).
//!
//! Positions carry the scalar type (they are what the gradient flows into); triangles, UVs,
//! part ids and smoothing groups are plain data. Normals are not differentiated (the loss sees
//! silhouettes only), so they are computed at the end from the finished positions: per corner,
//! the area-weighted average of the face normals around the vertex that share the triangle's
//! smoothing group and lie within [`CREASE_COS`] of its own normal (group 0 = flat shading).

use crate::ad::{Scalar, TapeVjp, Var, record};
use crate::{GenError, Lod, Mesh, ParamSpec, Part, Vjp, sanitize_params};
use glam::{DVec3, Vec2, Vec3};

/// Face normals further apart than this (cosine of 75°) never smooth into each other, so a
/// coarse level keeps its hard corners.
pub const CREASE_COS: f64 = 0.2588;
/// Cosine of half the crease angle (37.5°).
const CREASE_HALF_COS: f64 = 0.7934;

/// A point in space over scalar `S`.
pub type P3<S> = [S; 3];

/// A mesh being built.
#[derive(Clone, Debug)]
pub struct Builder<S> {
    /// Welded positions.
    pub pos: Vec<P3<S>>,
    /// Triangles, counter-clockwise seen from outside.
    pub tris: Vec<[u32; 3]>,
    /// Per-corner UVs.
    pub uvs: Vec<Vec2>,
    /// Part id per triangle.
    pub parts: Vec<u8>,
    /// Smoothing group per triangle (0 = flat).
    pub groups: Vec<u16>,
}

impl<S: Scalar> Builder<S> {
    /// An empty mesh.
    pub fn new() -> Self {
        Builder {
            pos: Vec::new(),
            tris: Vec::new(),
            uvs: Vec::new(),
            parts: Vec::new(),
            groups: Vec::new(),
        }
    }

    /// Adds a vertex and returns its index.
    pub fn vertex(&mut self, p: P3<S>) -> u32 {
        self.pos.push(p);
        (self.pos.len() - 1) as u32
    }

    /// Adds a triangle with its corner UVs.
    pub fn tri(&mut self, t: [u32; 3], uv: [Vec2; 3], part: u8, group: u16) {
        self.tris.push(t);
        self.uvs.extend_from_slice(&uv);
        self.parts.push(part);
        self.groups.push(group);
    }

    /// Adds a quad `a b c d` (counter-clockwise seen from outside) as two triangles.
    pub fn quad(&mut self, q: [u32; 4], uv: [Vec2; 4], part: u8, group: u16) {
        self.tri([q[0], q[1], q[2]], [uv[0], uv[1], uv[2]], part, group);
        self.tri([q[0], q[2], q[3]], [uv[0], uv[2], uv[3]], part, group);
    }

    /// Adds a closed convex polyhedron: `corners` are its vertices, `faces` its planar faces as
    /// corner-index loops, counter-clockwise seen from outside. Faces are fan-triangulated,
    /// flat-shaded, and get planar UVs in the mesh's units (metres for buildings): u along the
    /// face's first edge, v across it.
    pub fn polyhedron(&mut self, corners: &[P3<S>], faces: &[&[usize]], part: u8) {
        let first = self.pos.len() as u32;
        for &c in corners {
            self.vertex(c);
        }
        let val = |i: usize| {
            DVec3::new(
                corners[i][0].val(),
                corners[i][1].val(),
                corners[i][2].val(),
            )
        };
        for face in faces {
            let o = val(face[0]);
            let t = (val(face[1]) - o).normalize_or_zero();
            let n = (val(face[1]) - o).cross(val(face[2]) - o);
            let bt = n.cross(t).normalize_or_zero();
            let uv = |i: usize| {
                let d = val(i) - o;
                Vec2::new(d.dot(t) as f32, d.dot(bt) as f32)
            };
            for k in 1..face.len() - 1 {
                let (a, b, c) = (face[0], face[k], face[k + 1]);
                self.tri(
                    [first + a as u32, first + b as u32, first + c as u32],
                    [uv(a), uv(b), uv(c)],
                    part,
                    0,
                );
            }
        }
    }

    /// Adds an axis-aligned box from `lo` to `hi` (every component of `hi` above `lo`).
    pub fn cuboid(&mut self, lo: P3<S>, hi: P3<S>, part: u8) {
        // Corner (i, j, k) picks lo/hi in x, y, z; index 4i + 2j + k.
        let corners: [P3<S>; 8] = std::array::from_fn(|n| {
            let pick = |bit: usize, axis: usize| {
                if n >> bit & 1 == 1 {
                    hi[axis]
                } else {
                    lo[axis]
                }
            };
            [pick(2, 0), pick(1, 1), pick(0, 2)]
        });
        const FACES: [&[usize]; 6] = [
            &[0, 1, 3, 2], // −X
            &[4, 6, 7, 5], // +X
            &[0, 4, 5, 1], // −Y
            &[2, 3, 7, 6], // +Y
            &[0, 2, 6, 4], // −Z
            &[1, 5, 7, 3], // +Z
        ];
        self.polyhedron(&corners, &FACES, part);
    }

    /// The finished mesh (normals computed here) and the scalar positions.
    pub fn finish(self, parts: &[Part]) -> Result<(Mesh, Vec<P3<S>>), GenError> {
        let p64: Vec<DVec3> = self
            .pos
            .iter()
            .map(|p| DVec3::new(p[0].val(), p[1].val(), p[2].val()))
            .collect();
        let corner_normals = corner_normals(&p64, &self.tris, &self.groups);
        let mesh = Mesh {
            positions: p64.iter().map(|p| p.as_vec3()).collect(),
            triangles: self.tris,
            corner_normals,
            corner_uvs: self.uvs,
            tri_parts: self.parts,
            parts: parts.to_vec(),
        };
        mesh.check()?;
        Ok((mesh, self.pos))
    }
}

impl<S: Scalar> Default for Builder<S> {
    fn default() -> Self {
        Self::new()
    }
}

/// Per-corner normals with smoothing groups and a crease limit (see the module doc).
fn corner_normals(p: &[DVec3], tris: &[[u32; 3]], groups: &[u16]) -> Vec<Vec3> {
    // Area-weighted face normals (the cross product's length is twice the area).
    let face: Vec<DVec3> = tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| p[i as usize]);
            (b - a).cross(c - a)
        })
        .collect();
    let unit: Vec<DVec3> = face.iter().map(|n| n.normalize_or_zero()).collect();
    // Vertex → triangles, compressed rows.
    let mut start = vec![0u32; p.len() + 1];
    for t in tris {
        for &i in t {
            start[i as usize + 1] += 1;
        }
    }
    for i in 0..p.len() {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut adj = vec![0u32; 3 * tris.len()];
    for (ti, t) in tris.iter().enumerate() {
        for &i in t {
            adj[fill[i as usize] as usize] = ti as u32;
            fill[i as usize] += 1;
        }
    }
    // Fast path: a vertex whose faces all share one smoothing group and lie within half the
    // crease angle of one of them is smooth all round (any two of its faces are then within
    // the crease), so all its corners share one normal, computed once.
    let smooth: Vec<Option<DVec3>> = (0..p.len())
        .map(|v| {
            let rows = &adj[start[v] as usize..start[v + 1] as usize];
            let &first = rows.first()?;
            let (g, r) = (groups[first as usize], unit[first as usize]);
            let uniform = g != 0
                && rows
                    .iter()
                    .all(|&o| groups[o as usize] == g && unit[o as usize].dot(r) > CREASE_HALF_COS);
            uniform.then(|| {
                rows.iter()
                    .map(|&o| face[o as usize])
                    .sum::<DVec3>()
                    .normalize_or_zero()
            })
        })
        .collect();
    let mut out = Vec::with_capacity(3 * tris.len());
    for (ti, t) in tris.iter().enumerate() {
        let g = groups[ti];
        for &v in t {
            let n = if g == 0 {
                unit[ti]
            } else if let Some(n) = smooth[v as usize] {
                n
            } else {
                let rows = &adj[start[v as usize] as usize..start[v as usize + 1] as usize];
                rows.iter()
                    .map(|&o| o as usize)
                    .filter(|&o| groups[o] == g && unit[o].dot(unit[ti]) > CREASE_COS)
                    .map(|o| face[o])
                    .sum::<DVec3>()
                    .normalize_or_zero()
            };
            // A zero normal only comes from a degenerate triangle; keep the mesh finite.
            let n = if n == DVec3::ZERO { DVec3::Y } else { n };
            out.push(n.as_vec3());
        }
    }
    out
}

/// A generator body written once over [`Scalar`].
pub trait Model: Sync {
    /// The parameter spec.
    fn spec(&self) -> &[ParamSpec];
    /// The parts, indexed by the part ids the builder emits.
    fn parts(&self) -> &[Part];
    /// Builds the mesh from sanitised parameters (discrete ones are constants).
    fn build<S: Scalar>(&self, p: &[S], lod: Lod) -> Result<Builder<S>, GenError>;
}

/// `Generator::generate` for a [`Model`].
pub fn generate<M: Model>(m: &M, params: &[f64], lod: Lod) -> Result<Mesh, GenError> {
    let p = sanitize_params(m.spec(), params)?;
    Ok(m.build::<f64>(&p, lod)?.finish(m.parts())?.0)
}

/// `Generator::generate_with_vjp` for a [`Model`]: records the same build on a tape, with the
/// continuous parameters as inputs.
pub fn generate_with_vjp<M: Model>(
    m: &M,
    params: &[f64],
    lod: Lod,
) -> Result<(Mesh, Box<dyn Vjp>), GenError> {
    let p = sanitize_params(m.spec(), params)?;
    let (res, tape) = record(|| {
        let vars: Vec<Var> = m
            .spec()
            .iter()
            .zip(&p)
            .map(|(s, &v)| {
                if s.kind.is_continuous() {
                    Var::input(v)
                } else {
                    Var::cst(v)
                }
            })
            .collect();
        (m.build::<Var>(&vars, lod), vars)
    });
    let (built, vars) = res;
    let (mesh, pos) = built?.finish(m.parts())?;
    Ok((mesh, Box::new(TapeVjp::new(tape, &vars, &pos))))
}
