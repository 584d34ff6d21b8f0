//! Procedural generators for procfit: a parameter vector in, a mesh out.
//!
//! Every generator implements [`Generator`]: a parameter spec (names, labels, groups, ranges,
//! kinds), named presets, `generate(params, lod) -> Mesh`, and for the differentiable ones a
//! vector–Jacobian product that turns dL/d(vertex positions) into dL/d(params) (the paper's
//! eq. 2). Differentiable generators are written once over a scalar type so that the mesh and
//! its Jacobian come from the same code.
//!
//! Modules: [`ad`] is the reverse-mode tape and the [`ad::Scalar`] trait generators are written
//! over; [`build`] is the generic mesh builder and the glue that turns one generic build into
//! `generate` and `generate_with_vjp`; [`dish`] and [`building`] are the two differentiable
//! generators of the paper (§3.3, Algorithms 1 and 2).
//!
//! Conventions used by every generator:
//! - Y is up, units are metres-like, the object stands on or around the origin.
//! - Triangles are counter-clockwise seen from outside (outward normals by the right-hand rule).
//! - Positions are welded: a point shared by several triangles has one index, also along UV
//!   seams and hard edges. Normals and UVs are stored per triangle corner, so seams and creases
//!   need no duplicate positions; exporters split vertices where corners disagree.

use glam::{Vec2, Vec3};
use std::fmt;

pub mod ad;
pub mod build;
pub mod building;
pub mod dish;
pub mod rng;
pub mod tree;

/// Level of detail, from the coarse mesh used during the fit to the export mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Lod {
    /// Coarsest: used by the first optimisation stage.
    Low = 0,
    /// Medium detail.
    Medium = 1,
    /// High detail.
    High = 2,
    /// Finest: for export.
    Ultra = 3,
}

impl Lod {
    /// All levels, coarse to fine.
    pub const ALL: [Lod; 4] = [Lod::Low, Lod::Medium, Lod::High, Lod::Ultra];

    /// The level for an index 0..=3, or `None`.
    pub fn from_index(i: usize) -> Option<Lod> {
        Self::ALL.get(i).copied()
    }

    /// The index 0..=3 of this level.
    pub fn index(self) -> usize {
        self as usize
    }
}

/// What sort of value a parameter holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamKind {
    /// A real number in `[min, max]`; differentiable generators give it a derivative.
    Continuous,
    /// A whole number in `[min, max]`; zero derivative.
    Integer,
    /// 0 or 1; zero derivative.
    Boolean,
    /// One of the named choices, stored as its index; zero derivative.
    Categorical(&'static [&'static str]),
}

impl ParamKind {
    /// Whether the parameter can receive a gradient.
    pub fn is_continuous(self) -> bool {
        matches!(self, ParamKind::Continuous)
    }
}

/// Description of one parameter: what the optimiser, the page's sliders and the exporter see.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamSpec {
    /// Stable machine name, used in params JSON and glTF extras (`snake_case`).
    pub name: &'static str,
    /// Human label for a slider.
    pub label: &'static str,
    /// Group the page shows the slider under (e.g. "Body", "Handle", "Windows").
    pub group: &'static str,
    /// Unit shown next to the value ("m", "°", "" for ratios and counts).
    pub unit: &'static str,
    /// Smallest allowed value.
    pub min: f64,
    /// Largest allowed value.
    pub max: f64,
    /// Default value (inside the range).
    pub default: f64,
    /// Kind of value.
    pub kind: ParamKind,
}

/// The unit symbol of a length ([`ParamSpec::unit`]): scaling the whole model multiplies every
/// parameter in it.
pub const LENGTH_UNIT: &str = "m";

impl ParamSpec {
    /// Whether the parameter is a continuous length (unit [`LENGTH_UNIT`]): scaling the whole
    /// model by g multiplies it by g, and leaves counts, ratios and angles alone.
    pub fn is_length(&self) -> bool {
        self.kind.is_continuous() && self.unit == LENGTH_UNIT
    }
}

/// A spec serialises as the page's sliders read it: its fields, `kind` as `continuous`,
/// `integer`, `boolean` or `categorical`, and `choices` (the categorical names, else empty).
impl serde::Serialize for ParamSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let (kind, choices): (&str, &[&str]) = match self.kind {
            ParamKind::Continuous => ("continuous", &[]),
            ParamKind::Integer => ("integer", &[]),
            ParamKind::Boolean => ("boolean", &[]),
            ParamKind::Categorical(c) => ("categorical", c),
        };
        let mut st = s.serialize_struct("ParamSpec", 9)?;
        st.serialize_field("name", self.name)?;
        st.serialize_field("label", self.label)?;
        st.serialize_field("group", self.group)?;
        st.serialize_field("unit", self.unit)?;
        st.serialize_field("min", &self.min)?;
        st.serialize_field("max", &self.max)?;
        st.serialize_field("default", &self.default)?;
        st.serialize_field("kind", kind)?;
        st.serialize_field("choices", choices)?;
        st.end()
    }
}

/// A named parameter vector that looks like a real object.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Preset {
    /// Stable machine name (e.g. `mug`).
    pub name: &'static str,
    /// Human label (e.g. "Mug").
    pub label: &'static str,
    /// One value per parameter, in spec order.
    pub values: Vec<f64>,
}

impl Preset {
    /// A preset that is every parameter's default in `specs` except `changes` (index, value).
    pub fn from_defaults(
        name: &'static str,
        label: &'static str,
        specs: &[ParamSpec],
        changes: &[(usize, f64)],
    ) -> Preset {
        let mut values: Vec<f64> = specs.iter().map(|s| s.default).collect();
        for &(i, v) in changes {
            values[i] = v;
        }
        Preset {
            name,
            label,
            values,
        }
    }
}

/// A named part of a mesh (body, handle, wall, window glass, trunk, leaf…).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Part {
    /// Stable name; becomes the glTF node and material name.
    pub name: &'static str,
    /// Default linear RGBA base colour for the part's material.
    pub color: [f32; 4],
}

/// An indexed triangle mesh with per-corner attributes and a part id per triangle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Welded vertex positions.
    pub positions: Vec<Vec3>,
    /// Triangles as indices into `positions`, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Unit normal of each triangle corner: `corner_normals[3 * t + k]` for corner `k` of
    /// triangle `t`.
    pub corner_normals: Vec<Vec3>,
    /// Texture coordinate of each triangle corner, indexed like `corner_normals`.
    pub corner_uvs: Vec<Vec2>,
    /// Index into `parts` for each triangle.
    pub tri_parts: Vec<u8>,
    /// The parts this mesh is made of.
    pub parts: Vec<Part>,
}

impl Mesh {
    /// Checks the structural invariants every generator promises (lengths agree, indices in
    /// range, finite values). Geometric checks (watertight, orientation) live in the tests.
    pub fn check(&self) -> Result<(), GenError> {
        let nt = self.triangles.len();
        let bad = |what: String| Err(GenError::InvalidMesh(what));
        if self.tri_parts.len() != nt {
            return bad(format!(
                "{} part ids for {} triangles",
                self.tri_parts.len(),
                nt
            ));
        }
        if self.corner_normals.len() != 3 * nt || self.corner_uvs.len() != 3 * nt {
            return bad("corner attribute count is not 3 × triangles".into());
        }
        let nv = self.positions.len() as u32;
        if let Some(t) = self.triangles.iter().find(|t| t.iter().any(|&i| i >= nv)) {
            return bad(format!("triangle {t:?} indexes past {nv} vertices"));
        }
        if let Some(&p) = self
            .tri_parts
            .iter()
            .find(|&&p| usize::from(p) >= self.parts.len())
        {
            return bad(format!("part id {p} but only {} parts", self.parts.len()));
        }
        if !self.positions.iter().all(|p| p.is_finite())
            || !self.corner_normals.iter().all(|n| n.is_finite())
            || !self.corner_uvs.iter().all(|uv| uv.is_finite())
        {
            return bad("non-finite position, normal or uv".into());
        }
        Ok(())
    }

    /// Axis-aligned bounding box `(min, max)` of the positions, or `None` when empty.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
        )
    }
}

/// Everything that can go wrong when asking a generator for a mesh.
#[derive(Clone, Debug, PartialEq)]
pub enum GenError {
    /// The parameter vector has the wrong number of values.
    WrongLength {
        /// How many the generator takes.
        expected: usize,
        /// How many were given.
        got: usize,
    },
    /// A value is NaN or infinite.
    NotFinite {
        /// Name of the parameter.
        name: &'static str,
    },
    /// The generator has no derivatives.
    NotDifferentiable(&'static str),
    /// The adjoint given to a vector–Jacobian product does not match the mesh.
    AdjointLength {
        /// Vertex count of the mesh.
        expected: usize,
        /// Length of the adjoint.
        got: usize,
    },
    /// A generator produced a mesh that breaks its invariants (a bug; reported, not panicked).
    InvalidMesh(String),
}

impl fmt::Display for GenError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GenError::WrongLength { expected, got } => {
                write!(f, "expected {expected} parameter values, got {got}")
            }
            GenError::NotFinite { name } => write!(f, "parameter `{name}` is not a finite number"),
            GenError::NotDifferentiable(g) => write!(f, "generator `{g}` is not differentiable"),
            GenError::AdjointLength { expected, got } => {
                write!(f, "adjoint has {got} vertices, mesh has {expected}")
            }
            GenError::InvalidMesh(what) => write!(f, "generator produced an invalid mesh: {what}"),
        }
    }
}

impl std::error::Error for GenError {}

/// Checks a parameter vector against a spec and returns it with every value clamped into its
/// range, whole-number kinds rounded. Wrong length and NaN/∞ are errors; out-of-range values
/// are clamped (documented behaviour, so sliders and optimisers can overshoot safely).
pub fn sanitize_params(spec: &[ParamSpec], params: &[f64]) -> Result<Vec<f64>, GenError> {
    if spec.len() != params.len() {
        return Err(GenError::WrongLength {
            expected: spec.len(),
            got: params.len(),
        });
    }
    spec.iter()
        .zip(params)
        .map(|(s, &v)| {
            if !v.is_finite() {
                return Err(GenError::NotFinite { name: s.name });
            }
            let v = v.clamp(s.min, s.max);
            Ok(if s.kind.is_continuous() {
                v
            } else {
                v.round().clamp(s.min, s.max)
            })
        })
        .collect()
}

/// How a generator's parameters are fitted to photos.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FitMethod {
    /// Silhouettes over every photo: a memetic search, then Adam on the paper's eq. 1 through
    /// the generator's vector–Jacobian product (`procfit::reconstruct::Session`). Needs
    /// [`Generator::differentiable`]; `auto` tries every generator fitted this way.
    Gradients,
    /// The tree GA on one photo's branch/leaf labels (`procfit::tree::impostor`, paper §3.5):
    /// no gradients, the generator's `seed` parameter kept by a refit.
    TreeGa,
}

impl FitMethod {
    /// The name the page and the worker protocol use (`gradients`, `tree_ga`).
    pub fn as_str(self) -> &'static str {
        match self {
            FitMethod::Gradients => "gradients",
            FitMethod::TreeGa => "tree_ga",
        }
    }
}

/// Labels beyond the object mask that a generator's fit reads from a photo, and so the mask
/// tools the page shows for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaskExtra {
    /// The object mask is all.
    None,
    /// Window labels (façade, window) inside the mask: the window term of the fit.
    Windows,
    /// Branch/leaf labels from the photo's colours inside the mask (what the tree GA fits).
    TreeLabels,
}

impl MaskExtra {
    /// The name the page uses (`none`, `windows`, `tree_labels`).
    pub fn as_str(self) -> &'static str {
        match self {
            MaskExtra::None => "none",
            MaskExtra::Windows => "windows",
            MaskExtra::TreeLabels => "tree_labels",
        }
    }
}

/// What a generator can do, as data: the CLI, the worker and the page read this instead of
/// checking generator names.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capabilities {
    /// How it is fitted to photos; `None`: it is not (the page offers no fit for it).
    pub fit: Option<FitMethod>,
    /// The name a person chooses it by (the page's generator choice).
    pub display_name: &'static str,
    /// Export detail: the least level of detail a fitted model is shown and saved at (the
    /// CLI writes fits at [`Lod::High`] or this, whichever is finer).
    pub fitted_lod: Lod,
    /// The mask extras its fit reads.
    pub mask_extra: MaskExtra,
    /// Whole fits from different seeds that a fit at full effort makes, keeping the best
    /// (procfit's `FitConfig::restarts_for`): what one run costs and how often one lands in a
    /// wrong basin decide it. 1 for a fit that does not restart (the tree GA).
    pub fit_runs: usize,
    /// Below this photo-view IoU (the fitted model through its fitted camera against a
    /// photo's mask, don't-care excluded) a fit says the model does not match that photo:
    /// set from how closely a right fit of this generator outlines its photos, so that a
    /// wrong shape, a wrong kind of object or a mask holding more than the object shows.
    pub photo_match_level: f64,
    /// How much of the automatic mask's smoothness its last cut near the outline keeps
    /// (procfit's `segment::Options::outline_smoothing`, in (0, 1]): lower lets the photo's
    /// colours carry the outline into a corner where a shaded wall meets ground of a similar
    /// colour, higher keeps a rounded outline from taking in reflections and table grain.
    pub outline_smoothing: f32,
    /// Whether its shapes can reach further back or less far at the same front outline (a
    /// box's depth; a lathed dish's depth is its width): then a photo that shows no depth (a
    /// façade straight on, at eye level) leaves the depth a guess, and a fit checks for that
    /// (procfit's `eval::depth_agreement`).
    pub free_depth: bool,
}

/// The reverse-mode derivative of one generated mesh: maps dL/d(positions) to dL/d(params).
pub trait Vjp: Send + Sync {
    /// Adds `Σ_v d_positions[v] · d(position v)/d(params)` into `d_params` (one entry per
    /// parameter; discrete parameters get 0). Errors when `d_positions` does not have one entry
    /// per mesh vertex.
    fn vjp(&self, d_positions: &[Vec3], d_params: &mut [f64]) -> Result<(), GenError>;
}

/// Final losses within this ratio of the lowest count as a tie for [`Generator::tie_prior`]:
/// the silhouette cannot tell them apart (restarts of one fit end within a few per cent of
/// each other when they found the same shape).
pub const TIE_TOLERANCE: f64 = 0.06;

/// A procedural generator.
pub trait Generator: Send + Sync {
    /// Stable machine name (`dish`, `building`, `tree`).
    fn name(&self) -> &'static str;
    /// Human label.
    fn label(&self) -> &'static str;
    /// Version of the parameterisation; bumped when a parameter's meaning changes.
    fn version(&self) -> u32;
    /// The parameters, in vector order.
    fn params(&self) -> &[ParamSpec];
    /// Named presets.
    fn presets(&self) -> Vec<Preset>;
    /// Whether [`Generator::generate_with_vjp`] is available.
    fn differentiable(&self) -> bool;
    /// How it is fitted, shown and exported (see [`Capabilities`]).
    fn capabilities(&self) -> Capabilities;
    /// Builds the mesh. Parameters are validated with [`sanitize_params`].
    fn generate(&self, params: &[f64], lod: Lod) -> Result<Mesh, GenError>;
    /// Builds the mesh and its vector–Jacobian product from the same code path.
    fn generate_with_vjp(
        &self,
        params: &[f64],
        lod: Lod,
    ) -> Result<(Mesh, Box<dyn Vjp>), GenError> {
        let _ = (params, lod);
        Err(GenError::NotDifferentiable(self.name()))
    }
    /// Closed rings of `params`' mesh at `lod` that a photo shows as edges inside the
    /// silhouette: a dish's rim, where the inside meets the outside, and the foot of a cup
    /// standing on a saucer, where the cup meets the saucer. A fit reads the photo's edges along
    /// each ring's near half (the far half is on the outline), which fixes how high the camera
    /// is, and how deep a cup stands, where the outline alone cannot. Empty (the default) when
    /// the model has no such ring.
    fn edge_rings(&self, _params: &[f64], _lod: Lod) -> Vec<EdgeRing> {
        Vec::new()
    }
    /// How unlike a real object `params` look, for breaking ties between fits whose silhouettes
    /// match alike (one photo often cannot tell two shapes apart: a mug's handle turned towards
    /// the camera and a shorter one seen side-on). Never part of the loss: among restarts whose
    /// final losses tie ([`TIE_TOLERANCE`]), the fit keeps the lowest. 0 (no preference) by
    /// default.
    fn tie_prior(&self, params: &[f64]) -> f64 {
        let _ = params;
        0.0
    }
    /// A loss difference (eq. 1's units, a share of the image's pixels) below which restarts
    /// tie for [`Generator::tie_prior`] whatever their losses' ratio: where a few hundred
    /// pixels of outline say less about the shape than the prior does. Added to the lowest
    /// loss's [`TIE_TOLERANCE`]. 0 by default.
    fn tie_margin(&self) -> f64 {
        0.0
    }
    /// A penalty that keeps shapes sane, and its gradient (same length as `params`). Zero by
    /// default.
    fn regularizer(&self, params: &[f64]) -> (f64, Vec<f64>) {
        (0.0, vec![0.0; params.len()])
    }
    /// How unlike real objects' shapes `params` are where a photo may not show them, and its
    /// gradient (same length as `params`): the fit's gradient stages add it to the loss (the
    /// search leaves it out, so it does not choose between seeds). Zero by default.
    fn shape_prior(&self, params: &[f64]) -> (f64, Vec<f64>) {
        (0.0, vec![0.0; params.len()])
    }

    /// Seeds with an optional part that no regular seed has (a cup's saucer), and the range of
    /// parameters only that part uses: stage 1 screens the extras after [`Generator::seeds`]
    /// and keeps them only when one fits the views better than every regular seed; until then
    /// those parameters are not searched, so a photo without such a part is fitted exactly as
    /// if they did not exist. Defaults to none.
    fn extra_seeds(&self) -> (Vec<Vec<f64>>, std::ops::Range<usize>) {
        (Vec::new(), 0..0)
    }

    /// Categorical parameters whose choice 0 is the simpler structure and whose other choices
    /// add to it (a building's L-shaped footprint adds a wing to the rectangle). A part of the
    /// model that one view does not show costs nothing in eq. 1, so the fit's hand-over treats
    /// these as it treats Boolean parameters: Occam's step tries each at 0, and the best
    /// stage-1 individual of each other structure is probed too (stage 1 may reach a structure
    /// late and keep few individuals of it). None by default.
    fn structure_choices(&self) -> &'static [usize] {
        &[]
    }

    /// Stage 1's seeds for the runs a fit adds when its kept model does not match a photo
    /// (its photo-view IoU below [`Capabilities::photo_match_level`]): shapes the regular
    /// seeds' search rarely reaches and a wrong kept fit often misses (a building's L-shaped
    /// footprints). Empty by default: no runs are added.
    fn rescue_seeds(&self) -> Vec<Vec<f64>> {
        Vec::new()
    }

    /// Continuous parameters that refine a shape the seeds already make (a hip roof's ridge
    /// length): stage 1's mutation never changes them, only the gradient steps (stage 1's local
    /// searches, stages 2 and 3, whose steps are longer for them) move them from the seeds'
    /// values, so they add no dimension to the random search. Every other restart's seeds have
    /// them at the middle of their range instead, and the other restarts' hand-over also tries
    /// each of its starts with them there. None by default.
    fn refined_only(&self) -> &'static [usize] {
        &[]
    }

    /// The values of parameter `index` a fit keeps only when its finest stage's views ask for
    /// them (`None`, the default: every value): detail that stage 1 at LOW does not show and
    /// chooses blindly. When stage 3 (at its finer detail) starts, each parameter outside its
    /// range is tried at the nearest value inside it and kept there when the views fit as well
    /// (procfit's `handover::simplify_detail`), unless the fit starts from the user's model.
    fn plain_range(&self, _index: usize) -> Option<(f64, f64)> {
        None
    }

    /// What one photo cannot tell about a shape with these parameters, however well the fit
    /// outlines it, and what to do: said after every fit from one photo (procfit's
    /// `eval::one_view_caveat`). `None` by default.
    fn one_view_caveat(&self, _params: &[f64]) -> Option<&'static str> {
        None
    }

    /// The initial population the memetic optimiser starts from (paper §3.2: presets are
    /// concatenated into the initial population). Defaults to the presets' values.
    fn seeds(&self) -> Vec<Vec<f64>> {
        self.presets().into_iter().map(|p| p.values).collect()
    }

    /// Default parameter vector.
    fn defaults(&self) -> Vec<f64> {
        self.params().iter().map(|p| p.default).collect()
    }

    /// A preset that is this generator's defaults except `changes` (index, value): how a
    /// generator whose presets differ from its defaults in a few places writes them.
    fn preset_from_defaults(
        &self,
        name: &'static str,
        label: &'static str,
        changes: &[(usize, f64)],
    ) -> Preset {
        Preset::from_defaults(name, label, self.params(), changes)
    }

    /// The preset with this name.
    fn preset(&self, name: &str) -> Option<Preset> {
        self.presets().into_iter().find(|p| p.name == name)
    }
}

/// Every generator procfit knows, in the order the page lists them: the one registration
/// list (a new generator is its own file plus one entry here).
pub fn all() -> Vec<&'static dyn Generator> {
    vec![&dish::Dish, &building::Building, &tree::TreeGenerator]
}

/// The generator with this machine name.
pub fn by_name(name: &str) -> Option<&'static dyn Generator> {
    all().into_iter().find(|g| g.name() == name)
}

/// A closed ring of a mesh's vertices that a photo shows as an edge inside the silhouette
/// ([`Generator::edge_rings`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EdgeRing {
    /// The ring's vertices, in order around it.
    pub vertices: Vec<u32>,
    /// Rings further up the surface from [`EdgeRing::vertices`], lowest first, each as long
    /// and in the same order: the edge is then, around the ring, where the surface going up
    /// first faces the camera (the lower occluding contour: a straight cup's foot, a bulging
    /// teacup's belly). Empty: the ring itself, always taken as seen (a rim's edge against the
    /// cup's inside, from every camera above it).
    pub above: Vec<Vec<u32>>,
    /// A ring in front whose projection a point must lie inside to be seen (the saucer's rim
    /// around a cup's foot: from low, the saucer's front hides the foot). Empty: none.
    pub seen_within: Vec<u32>,
}
