//! The independent building benchmark (issue 15): buildings procfit's generator did not make,
//! written here as plain triangle meshes (boxes and L-shaped footprints; gable, hip, flat and
//! shed roofs; chimneys, dormers, windows and doors; one to eight floors), each seen by one
//! camera 5°–30° above the ground, and their scoring by the paper's IoU-64.
//!
//! Per case there are four inputs: the clean mask (the mesh's silhouette through
//! [`crate::render`], binarised) and three photo-like images of it — on a plain background, on
//! a sky-and-ground gradient and on textured ground (grass and cobble noise seen in
//! perspective) — each segmented by [`crate::segment::segment_auto_with`] as the CLI does with a
//! user's photo. The photos are drawn by [`LabelRenderer`] with one label per part and shade
//! (flat Lambert shading under a fixed sun), composited over the background with noise.
//!
//! Scoring follows the dish and building recovery tests: the fit is moved into the truth's frame
//! through view 0 ([`align_to_reference`], the truth's object transform is known) and compared
//! over the 64 turntable views ([`iou64`], 128²); the photo-view IoU is the fit through its own
//! fitted camera against the true mask. From a photo, the fitted model's wall and roof colours
//! measured in it ([`crate::colors`], issue 17) are compared with the colours it was drawn with
//! (CIE76 ΔE, [`BenchScore::colour_de`]). The paper's own test building is read from a path given
//! at run time (it has no licence and never enters the repository).
//! `cargo bench --bench building_bench` prints the table; `tests/building_bench.rs` runs two
//! cases at a reduced budget.

use crate::bench_cases::BenchFit;
use crate::camera::View;
use crate::generators::building::idx;
use crate::generators::{Generator, Lod, Mesh, Part};
use crate::mask::{LabelImage, Mask};
use crate::reconstruct::eval::{self, view_iou};
use crate::reconstruct::views::ViewVars;
use crate::reconstruct::{
    FitConfig, FitError, FitResult, Session, align_to_reference, iou64, render_coverage,
};
use crate::render::labels::LabelRenderer;
use crate::segment::{self, Photo};
use glam::{DVec3, Vec2, Vec3};
use std::path::Path;

/// Side of every benchmark image (the recovery tests' mask size).
pub const SIDE: u32 = 256;
/// Vertical field of view of every benchmark camera, radians (known to the fit, as EXIF gives).
pub const FOV_Y: f64 = 0.5;
/// The parts of a benchmark mesh, in part-id order.
pub const PARTS: [&str; 5] = ["wall", "roof", "window", "door", "chimney"];
const WALL: u8 = 0;
const ROOF: u8 = 1;
const WINDOW: u8 = 2;
const DOOR: u8 = 3;
const CHIMNEY: u8 = 4;
/// Base colours (sRGB 0..1) of the parts in photos.
const COLOURS: [[f32; 3]; 5] = [
    [0.86, 0.80, 0.70],
    [0.55, 0.22, 0.16],
    [0.18, 0.24, 0.32],
    [0.40, 0.25, 0.14],
    [0.50, 0.30, 0.26],
];
/// Shade levels per part in the label image.
const SHADES: u8 = 12;

/// Writes closed triangle meshes: every solid added is closed and oriented outward by itself.
#[derive(Default)]
struct Writer {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    parts: Vec<u8>,
}

impl Writer {
    /// A convex solid from its corners and faces (corner indices around each face, either
    /// order): each face is turned to face away from the solid's centre and fanned.
    fn convex(&mut self, corners: &[[f32; 3]], faces: &[&[usize]], part: u8) {
        let base = self.positions.len() as u32;
        let pts: Vec<Vec3> = corners.iter().map(|&c| Vec3::from_array(c)).collect();
        let centre = pts.iter().copied().sum::<Vec3>() / pts.len() as f32;
        self.positions.extend(&pts);
        for f in faces {
            // Newell's normal of the face as listed.
            let mut n = Vec3::ZERO;
            for k in 0..f.len() {
                let (a, b) = (pts[f[k]], pts[f[(k + 1) % f.len()]]);
                n += Vec3::new(
                    (a.y - b.y) * (a.z + b.z),
                    (a.z - b.z) * (a.x + b.x),
                    (a.x - b.x) * (a.y + b.y),
                );
            }
            let fc = f.iter().map(|&i| pts[i]).sum::<Vec3>() / f.len() as f32;
            let outward = n.dot(fc - centre) >= 0.0;
            for k in 1..f.len() - 1 {
                let (a, b, c) = (f[0] as u32, f[k] as u32, f[k + 1] as u32);
                let t = if outward { [a, b, c] } else { [a, c, b] };
                self.triangles.push(t.map(|i| base + i));
                self.parts.push(part);
            }
        }
    }

    /// An axis-aligned box.
    fn cuboid(&mut self, lo: [f32; 3], hi: [f32; 3], part: u8) {
        let c = |i: usize| {
            [
                if i & 1 != 0 { hi[0] } else { lo[0] },
                if i & 2 != 0 { hi[1] } else { lo[1] },
                if i & 4 != 0 { hi[2] } else { lo[2] },
            ]
        };
        let corners: Vec<[f32; 3]> = (0..8).map(c).collect();
        self.convex(
            &corners,
            &[
                &[0, 1, 3, 2],
                &[4, 5, 7, 6],
                &[0, 1, 5, 4],
                &[2, 3, 7, 6],
                &[0, 2, 6, 4],
                &[1, 3, 7, 5],
            ],
            part,
        );
    }

    fn finish(self) -> Mesh {
        let n = self.triangles.len();
        let corner_normals = self
            .triangles
            .iter()
            .flat_map(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize]);
                [(b - a).cross(c - a).normalize_or(Vec3::Y); 3]
            })
            .collect();
        Mesh {
            positions: self.positions,
            triangles: self.triangles,
            corner_normals,
            corner_uvs: vec![Vec2::ZERO; 3 * n],
            tri_parts: self.parts,
            parts: PARTS
                .iter()
                .zip(COLOURS)
                .map(|(&name, c)| Part {
                    name,
                    color: [c[0], c[1], c[2], 1.0],
                })
                .collect(),
        }
    }
}

/// A rectangle of the footprint: `x0..x1 × z0..z1` (metres).
#[derive(Clone, Copy, Debug)]
struct Rect {
    x0: f32,
    x1: f32,
    z0: f32,
    z1: f32,
}

/// The roof over one wing.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Roof {
    /// A slab of this thickness.
    Flat(f32),
    /// Ridge along the wing's longer side, this pitch (degrees).
    Gable(f32),
    /// Four slopes of this pitch.
    Hip(f32),
    /// One slope rising towards −Z, this pitch.
    Shed(f32),
}

/// One wing: its footprint, wall height, floors and roof.
#[derive(Clone, Copy, Debug)]
struct Wing {
    rect: Rect,
    floors: u32,
    floor_height: f32,
    roof: Roof,
    overhang: f32,
}

impl Wing {
    fn eave(&self) -> f32 {
        self.floors as f32 * self.floor_height
    }

    /// Walls, windows on every floor of all four sides, and the roof.
    fn write(&self, w: &mut Writer) {
        let r = self.rect;
        let top = self.eave();
        w.cuboid([r.x0, 0.0, r.z0], [r.x1, top, r.z1], WALL);
        let proud = 0.06;
        for floor in 0..self.floors {
            let y0 = floor as f32 * self.floor_height + 0.3 * self.floor_height;
            let y1 = y0 + 0.5 * self.floor_height;
            // Along X (front and back) and along Z (sides), one window every 2.5 m.
            for (a0, a1, along_x) in [(r.x0, r.x1, true), (r.z0, r.z1, false)] {
                let n = ((a1 - a0) / 2.5).floor().max(1.0) as usize;
                let step = (a1 - a0) / n as f32;
                for k in 0..n {
                    let c = a0 + step * (k as f32 + 0.5);
                    let (b0, b1) = (c - 0.3 * step, c + 0.3 * step);
                    if along_x {
                        w.cuboid([b0, y0, r.z1], [b1, y1, r.z1 + proud], WINDOW);
                        w.cuboid([b0, y0, r.z0 - proud], [b1, y1, r.z0], WINDOW);
                    } else {
                        w.cuboid([r.x1, y0, b0], [r.x1 + proud, y1, b1], WINDOW);
                        w.cuboid([r.x0 - proud, y0, b0], [r.x0, y1, b1], WINDOW);
                    }
                }
            }
        }
        roof(w, r, top, self.roof, self.overhang);
    }

    /// Height of the roof's top above the ground.
    fn ridge(&self) -> f32 {
        let r = self.rect;
        let (lx, lz) = (r.x1 - r.x0, r.z1 - r.z0);
        let run = 0.5 * lx.min(lz) + self.overhang;
        self.eave()
            + match self.roof {
                Roof::Flat(t) => t,
                Roof::Gable(p) | Roof::Hip(p) => run * p.to_radians().tan() + 0.2,
                Roof::Shed(p) => (lz + 2.0 * self.overhang) * p.to_radians().tan() + 0.2,
            }
    }
}

/// A roof over `r` from height `y` (fascia 0.2 m, then the slopes).
fn roof(w: &mut Writer, r: Rect, y: f32, kind: Roof, oh: f32) {
    let (x0, x1, z0, z1) = (r.x0 - oh, r.x1 + oh, r.z0 - oh, r.z1 + oh);
    let fascia = 0.2;
    let yb = y + fascia;
    let bottom = [[x0, y, z0], [x1, y, z0], [x1, y, z1], [x0, y, z1]];
    let mut c: Vec<[f32; 3]> = bottom.to_vec();
    c.extend(bottom.iter().map(|p| [p[0], yb, p[2]]));
    let sides: [&[usize]; 5] = [
        &[0, 1, 2, 3],
        &[0, 1, 5, 4],
        &[1, 2, 6, 5],
        &[2, 3, 7, 6],
        &[3, 0, 4, 7],
    ];
    match kind {
        Roof::Flat(t) => {
            w.cuboid([x0, y, z0], [x1, y + t, z1], ROOF);
        }
        Roof::Shed(p) => {
            let rise = (z1 - z0) * p.to_radians().tan();
            c[4][1] += rise;
            c[5][1] += rise;
            let top: &[usize] = &[4, 5, 6, 7];
            let mut f = sides.to_vec();
            f.push(top);
            w.convex(&c, &f, ROOF);
        }
        Roof::Gable(p) | Roof::Hip(p) => {
            let along_x = x1 - x0 >= z1 - z0;
            let half = 0.5 * (x1 - x0).min(z1 - z0);
            let rise = half * p.to_radians().tan();
            let (cx, cz) = (0.5 * (x0 + x1), 0.5 * (z0 + z1));
            let inset = if matches!(kind, Roof::Hip(_)) {
                half
            } else {
                0.0
            };
            let yr = yb + rise;
            let (a, b) = if along_x {
                ([x0 + inset, yr, cz], [x1 - inset, yr, cz])
            } else {
                ([cx, yr, z0 + inset], [cx, yr, z1 - inset])
            };
            c.push(a);
            c.push(b);
            // Corners 4..8 at the fascia's top, ridge 8 (low end) and 9 (high end).
            let f: Vec<&[usize]> = if along_x {
                vec![&[4, 5, 9, 8], &[7, 6, 9, 8], &[4, 7, 8], &[5, 6, 9]]
            } else {
                vec![&[4, 7, 9, 8], &[5, 6, 9, 8], &[4, 5, 8], &[7, 6, 9]]
            };
            let mut all = sides.to_vec();
            all.extend(f);
            w.convex(&c, &all, ROOF);
        }
    }
}

/// A dormer on the +Z slope of a gable or hip wing: a box from below the slope at the eave
/// line, its front 0.3 m behind the wall and 1.4 m proud of the roof, reaching back into the
/// roof, with a little gable roof along Z; centred at `x`, `width` wide.
fn dormer(w: &mut Writer, wing: &Wing, x: f32, width: f32) {
    let r = wing.rect;
    let (Roof::Gable(p) | Roof::Hip(p)) = wing.roof else {
        return;
    };
    let t = p.to_radians().tan();
    let oh = wing.overhang;
    let ys = wing.eave() + 0.2;
    let zf = r.z1 - 0.3;
    // The roof surface at `zf` is (oh + 0.3)·t above `ys`; the box ends where it is `h` up.
    let h = 1.4 + (oh + 0.3) * t;
    let zb = r.z1 + oh - h / t - 0.3;
    let (a, b) = (x - 0.5 * width, x + 0.5 * width);
    w.cuboid([a, ys, zb], [b, ys + h, zf], WALL);
    let yt = ys + h;
    w.cuboid(
        [a + 0.2 * width, yt - 1.2, zf],
        [b - 0.2 * width, yt - 0.2, zf + 0.05],
        WINDOW,
    );
    let rise = 0.5 * (width + 0.3) * t;
    let (a, b) = (a - 0.15, b + 0.15);
    let c = [
        [a, yt, zb],
        [b, yt, zb],
        [b, yt, zf + 0.2],
        [a, yt, zf + 0.2],
        [x, yt + rise, zb],
        [x, yt + rise, zf + 0.2],
    ];
    w.convex(
        &c,
        &[
            &[0, 1, 2, 3],
            &[0, 3, 5, 4],
            &[1, 2, 5, 4],
            &[0, 1, 4],
            &[3, 2, 5],
        ],
        ROOF,
    );
}

/// A chimney at `(x, z)` from inside the building to `above` over the wing's ridge.
fn chimney(w: &mut Writer, wing: &Wing, x: f32, z: f32, above: f32) {
    let y0 = wing.eave() - 0.5;
    let y1 = wing.ridge() + above;
    w.cuboid([x - 0.35, y0, z - 0.35], [x + 0.35, y1, z + 0.35], CHIMNEY);
}

/// A door in the middle of a wing's +Z façade.
fn door(w: &mut Writer, wing: &Wing) {
    let r = wing.rect;
    let x = 0.5 * (r.x0 + r.x1);
    w.cuboid([x - 0.5, 0.0, r.z1], [x + 0.5, 2.1, r.z1 + 0.08], DOOR);
}

/// One benchmark building and the camera of its photo.
#[derive(Clone, Debug)]
pub struct BenchBuilding {
    /// Case name.
    pub name: &'static str,
    /// What it is, in a few words.
    pub kind: &'static str,
    /// The truth mesh (metres, Y up, standing on y = 0), parts [`PARTS`].
    pub mesh: Mesh,
    /// The photo's camera: the object transform in front of the fixed camera.
    pub view: View,
}

/// The object transform that shows `mesh` spun by `yaw` from `pitch` above (radians), filling
/// about 55 % of the image height, centred.
pub fn case_view(mesh: &Mesh, yaw: f64, pitch: f64) -> Result<View, FitError> {
    let (lo, hi) = mesh
        .bounds()
        .ok_or_else(|| FitError("a benchmark mesh is empty".into()))?;
    let vars = ViewVars {
        yaw,
        pitch,
        roll: 0.0,
        tx: 0.0,
        ty: 0.0,
        log_scale: 0.0,
        fov_y: FOV_Y,
    };
    Ok(vars.framing(lo, hi, 1.1).view(SIDE, SIDE))
}

fn rect(x0: f32, x1: f32, z0: f32, z1: f32) -> Rect {
    Rect { x0, x1, z0, z1 }
}

fn wing(rect: Rect, floors: u32, floor_height: f32, roof: Roof, overhang: f32) -> Wing {
    Wing {
        rect,
        floors,
        floor_height,
        roof,
        overhang,
    }
}

/// The benchmark's building called `name` (one of [`cases`]).
pub fn case_named(name: &str) -> Result<BenchBuilding, FitError> {
    cases()?
        .into_iter()
        .find(|c| c.name == name)
        .ok_or_else(|| FitError(format!("no benchmark building is called {name}")))
}

/// The benchmark's buildings, in a fixed order, with their cameras (elevations 5°–30°).
pub fn cases() -> Result<Vec<BenchBuilding>, FitError> {
    let deg = |d: f64| d.to_radians();
    let mut out = Vec::new();
    let mut add = |name, kind, build: &dyn Fn(&mut Writer), yaw: f64, pitch: f64| {
        let mut w = Writer::default();
        build(&mut w);
        let mesh = w.finish();
        let view = case_view(&mesh, yaw, pitch)?;
        out.push(BenchBuilding {
            name,
            kind,
            mesh,
            view,
        });
        Ok::<(), FitError>(())
    };
    add(
        "gable-chimney",
        "box, 2 floors, gable roof, chimney",
        &|w| {
            let a = wing(rect(-5.0, 5.0, -3.5, 3.5), 2, 2.8, Roof::Gable(38.0), 0.4);
            a.write(w);
            door(w, &a);
            chimney(w, &a, 2.5, -1.0, 0.6);
        },
        deg(35.0),
        deg(12.0),
    )?;
    add(
        "hip-bungalow",
        "box, 1 floor, hip roof",
        &|w| {
            let a = wing(rect(-6.5, 6.5, -4.5, 4.5), 1, 3.0, Roof::Hip(25.0), 0.6);
            a.write(w);
            door(w, &a);
        },
        deg(-30.0),
        deg(20.0),
    )?;
    add(
        "flat-block",
        "box, 5 floors, flat roof with a stair house",
        &|w| {
            let a = wing(rect(-10.0, 10.0, -6.0, 6.0), 5, 3.0, Roof::Flat(0.5), 0.1);
            a.write(w);
            door(w, &a);
            w.cuboid([2.0, 15.0, -3.0], [5.0, 17.6, 0.0], WALL);
        },
        deg(55.0),
        deg(8.0),
    )?;
    add(
        "shed-studio",
        "box, 2 floors, shed roof",
        &|w| {
            let a = wing(rect(-4.5, 4.5, -3.0, 3.0), 2, 2.7, Roof::Shed(15.0), 0.3);
            a.write(w);
            door(w, &a);
        },
        deg(25.0),
        deg(15.0),
    )?;
    add(
        "l-gable",
        "L-shape, 2 floors, crossed gable roofs, chimney",
        &|w| {
            let a = wing(rect(-6.0, 6.0, -3.5, 3.5), 2, 2.8, Roof::Gable(35.0), 0.4);
            let b = wing(rect(2.0, 6.0, -3.5, 8.0), 2, 2.8, Roof::Gable(35.0), 0.4);
            a.write(w);
            b.write(w);
            door(w, &a);
            chimney(w, &a, -3.0, 0.0, 0.5);
        },
        deg(-40.0),
        deg(18.0),
    )?;
    add(
        "l-flat",
        "L-shape, 3 floors, flat roofs",
        &|w| {
            let a = wing(rect(-9.0, 9.0, -5.0, 5.0), 3, 3.2, Roof::Flat(0.4), 0.15);
            let b = wing(rect(-9.0, -1.0, -5.0, 12.0), 3, 3.2, Roof::Flat(0.4), 0.15);
            a.write(w);
            b.write(w);
            door(w, &a);
        },
        deg(40.0),
        deg(25.0),
    )?;
    add(
        "gable-dormers",
        "box, 1 floor and attic, gable roof, two dormers",
        &|w| {
            let a = wing(rect(-6.0, 6.0, -4.5, 4.5), 1, 3.0, Roof::Gable(45.0), 0.5);
            a.write(w);
            door(w, &a);
            dormer(w, &a, -2.5, 1.8);
            dormer(w, &a, 2.5, 1.8);
            chimney(w, &a, 0.0, -1.5, 0.5);
        },
        deg(20.0),
        deg(10.0),
    )?;
    add(
        "hip-dormers",
        "box, 3 floors, hip roof, dormers, chimney",
        &|w| {
            let a = wing(rect(-7.0, 7.0, -5.0, 5.0), 3, 3.0, Roof::Hip(30.0), 0.6);
            a.write(w);
            door(w, &a);
            dormer(w, &a, -2.5, 1.6);
            dormer(w, &a, 2.5, 1.6);
            chimney(w, &a, 3.0, -2.0, 0.4);
        },
        deg(-25.0),
        deg(28.0),
    )?;
    add(
        "tower",
        "box, 8 floors, flat roof",
        &|w| {
            let a = wing(rect(-5.0, 5.0, -5.0, 5.0), 8, 3.0, Roof::Flat(0.6), 0.2);
            a.write(w);
            door(w, &a);
        },
        deg(30.0),
        deg(6.0),
    )?;
    add(
        "l-hip",
        "L-shape, 2 floors, hip roofs",
        &|w| {
            let a = wing(rect(-7.0, 5.0, -4.0, 4.0), 2, 3.0, Roof::Hip(28.0), 0.5);
            let b = wing(rect(-7.0, -1.0, -4.0, 9.0), 2, 3.0, Roof::Hip(28.0), 0.5);
            a.write(w);
            b.write(w);
            door(w, &a);
        },
        deg(50.0),
        deg(14.0),
    )?;
    Ok(out)
}

/// The paper's three cameras on its test building: (yaw, elevation) in degrees.
///
/// Where its fits go wrong (measured with `cargo bench --bench building_bench -- --each paper`,
/// which prints every run's loss, photo-view IoU and proportions): the runs that outline its mask
/// best are often not the right shape. From (−55°, 18°) at seed 3 the kept run is too tall for its
/// footprint (bounding box 1.73 × 1.47 its height, IoU-64 0.886) with a lower loss than the runs of
/// about 1.89 × 1.65 (IoU-64 0.958–0.964); at seed 1 (0.886 too) it has their proportions, its
/// error lies elsewhere. At quality 2 the wrong runs' losses fall further (from (−55°, 18°) both
/// seeds keep a 1.70 × 1.50; seeds 1 / 3, the mean of the three cameras 0.930 / 0.883 → 0.870 /
/// 0.903). Not the roof's four small boxes alone: without them (the truth edited, not kept) 0.919 /
/// 0.932, from (140°, 28°) still 0.886 / 0.905. Making thin one-contact spurs of any reach don't
/// care (`reconstruct::extras` with no least reach, the boxes' outline ignored): from (−55°, 18°)
/// the means over seeds 0–4 0.922 → 0.948, but from (30°, 8°) 0.951 → 0.907 and from (140°, 28°)
/// 0.920 → 0.895, in all 0.931 → 0.917. Not kept.
pub const PAPER_CAMERAS: [(f64, f64); 3] = [(30.0, 8.0), (-55.0, 18.0), (140.0, 28.0)];

/// The paper's test building (`building_test_2_original.obj`, Y up) from `path`, or `None`
/// when the file is absent. Its parts are not known: every triangle is wall.
pub fn paper_building(path: &Path) -> Result<Option<Mesh>, FitError> {
    let Ok(bytes) = std::fs::read(path) else {
        return Ok(None);
    };
    let r =
        crate::glb::import_obj(&bytes).map_err(|e| FitError(format!("{}: {e}", path.display())))?;
    let mut w = Writer {
        positions: r.positions,
        parts: vec![WALL; r.triangles.len()],
        triangles: r.triangles,
    };
    // Lift it onto the ground like the others (it is centred on the origin).
    let lo = w.positions.iter().fold(f32::MAX, |m, p| m.min(p.y));
    for p in &mut w.positions {
        p.y -= lo;
    }
    Ok(Some(w.finish()))
}

/// The inputs of a case, as the bench's columns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Input {
    /// The clean silhouette.
    Mask,
    /// A photo on a plain background.
    Plain,
    /// A photo over a sky-and-ground gradient.
    Gradient,
    /// A photo on textured ground (grass and cobbles) under a sky.
    Textured,
}

impl Input {
    /// All inputs, in column order.
    pub const ALL: [Input; 4] = [Input::Mask, Input::Plain, Input::Gradient, Input::Textured];

    /// The column name.
    pub fn name(self) -> &'static str {
        match self {
            Input::Mask => "mask",
            Input::Plain => "plain",
            Input::Gradient => "gradient",
            Input::Textured => "textured",
        }
    }
}

/// The clean mask of `mesh` through `view` (coverage ≥ ½ is object, as a segmented photo).
pub fn true_mask(mesh: &Mesh, view: &View) -> Result<Mask, FitError> {
    let c = render_coverage(mesh, view).map_err(FitError)?;
    Mask::new(
        view.width,
        view.height,
        c.iter()
            .map(|&v| if v >= 0.5 { 1.0 } else { 0.0 })
            .collect(),
    )
    .map_err(|e| FitError(e.0))
}

/// A hash of integer lattice coordinates to 0..1.
fn hash(x: i64, y: i64, seed: u64) -> f32 {
    let mut h = (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ seed.wrapping_mul(0x1656_67B1_9E37_79F9);
    h ^= h >> 31;
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h ^= h >> 29;
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// Smooth value noise at `(x, y)` in lattice units, 0..1.
fn value_noise(x: f32, y: f32, seed: u64) -> f32 {
    let (xf, yf) = (x.floor(), y.floor());
    let (ix, iy) = (xf as i64, yf as i64);
    let (u, v) = (x - xf, y - yf);
    let (u, v) = (u * u * (3.0 - 2.0 * u), v * v * (3.0 - 2.0 * v));
    let a = hash(ix, iy, seed) + u * (hash(ix + 1, iy, seed) - hash(ix, iy, seed));
    let b = hash(ix, iy + 1, seed) + u * (hash(ix + 1, iy + 1, seed) - hash(ix, iy + 1, seed));
    a + v * (b - a)
}

/// The textured ground at `(x, z)` metres: grass (multi-octave noise), with a cobbled path
/// (cells of random grey with dark joints) across it.
fn ground_texture(x: f32, z: f32) -> [f32; 3] {
    let path = (z - 0.35 * x - 14.0).abs() < 3.0 || (x + 12.0).abs() < 2.0;
    if path {
        let (cx, cz) = (x / 0.45, z / 0.45);
        let (fx, fz) = (cx - cx.floor(), cz - cz.floor());
        let joint = fx.min(1.0 - fx).min(fz.min(1.0 - fz)) < 0.08;
        let g = 0.35 + 0.35 * hash(cx.floor() as i64, cz.floor() as i64, 7);
        let g = if joint { 0.18 } else { g };
        return [g, g * 0.97, g * 0.92];
    }
    let n = 0.5 * value_noise(x * 1.7, z * 1.7, 1)
        + 0.3 * value_noise(x * 5.3, z * 5.3, 2)
        + 0.2 * value_noise(x * 13.0, z * 13.0, 3);
    let dry = value_noise(x * 0.3, z * 0.3, 4);
    [
        0.18 + 0.25 * n + 0.15 * dry,
        0.32 + 0.30 * n + 0.05 * dry,
        0.10 + 0.12 * n,
    ]
}

/// The background colour of pixel `(px, py)` for `input`, the ground being the plane y = 0 of
/// the object's frame seen through `view`.
fn background(input: Input, view: &View, px: f64, py: f64) -> [f32; 3] {
    if input == Input::Plain {
        return [0.80, 0.82, 0.86];
    }
    // The pixel's ray in the object's frame: camera-space direction, then world, then object.
    let f = view.focal();
    let (w, h) = (f64::from(view.width), f64::from(view.height));
    let d_cam = DVec3::new((px - 0.5 * w) / f, -(py - 0.5 * h) / f, -1.0);
    let d_world = view.pose.rotation * d_cam;
    let r = view.params.rotation_and_derivatives()[0];
    let p = &view.params;
    let origin = r.transpose() * (view.pose.position - p.translation) / p.scale;
    let dir = r.transpose() * d_world;
    let sky = |up: f64| {
        let t = (up * 4.0).clamp(0.0, 1.0) as f32;
        [0.85 - 0.35 * t, 0.88 - 0.25 * t, 0.95 - 0.05 * t]
    };
    let up = dir.y / dir.length();
    if up >= 0.0 {
        return sky(up);
    }
    let lambda = -origin.y / dir.y;
    let g = origin + lambda * dir;
    if input == Input::Gradient {
        let t = (-up * 3.0).clamp(0.0, 1.0) as f32;
        return [0.62 - 0.2 * t, 0.66 - 0.15 * t, 0.55 - 0.2 * t];
    }
    ground_texture(g.x as f32, g.z as f32)
}

/// A photo-like image of `mesh` through `view` over the background of `input` (not
/// [`Input::Mask`]): RGBA8, `view.width × view.height`. Parts in fixed colours, flat-shaded by a
/// fixed sun, a fine plaster/tile noise on the surfaces and sensor noise everywhere.
pub fn photo(mesh: &Mesh, view: &View, input: Input) -> Result<Vec<u8>, FitError> {
    let e = |x: crate::render::RenderError| FitError(x.0);
    let sun = Vec3::new(0.45, 0.8, 0.55).normalize();
    let labels: Vec<u8> = mesh
        .triangles
        .iter()
        .zip(&mesh.tri_parts)
        .map(|(t, &part)| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let n = (b - a).cross(c - a).normalize_or(Vec3::Y);
            let shade = 0.45 + 0.55 * n.dot(sun).max(0.0);
            let level = ((shade * f32::from(SHADES)) as u8).min(SHADES - 1);
            part.min(PARTS.len() as u8 - 1) * SHADES + level
        })
        .collect();
    let n_labels = PARTS.len() * usize::from(SHADES);
    let mut r = LabelRenderer::new(view.width, view.height, 3).map_err(e)?;
    let cov = r
        .render(&mesh.positions, &mesh.triangles, &labels, n_labels, view)
        .map_err(e)?;
    let (w, h) = (view.width as usize, view.height as usize);
    let n = w * h;
    let mut out = vec![255u8; 4 * n];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let bg = background(input, view, x as f64 + 0.5, y as f64 + 0.5);
            let mut rgb = [0.0f32; 3];
            let mut total = 0.0f32;
            for l in 0..n_labels {
                let c = cov[l * n + i];
                if c <= 0.0 {
                    continue;
                }
                let part = l / usize::from(SHADES);
                let shade = (l % usize::from(SHADES)) as f32 / f32::from(SHADES);
                let grain = 0.9 + 0.2 * hash(x as i64 / 2, y as i64 / 2, 11 + part as u64);
                for k in 0..3 {
                    rgb[k] += c * COLOURS[part][k] * shade * grain;
                }
                total += c;
            }
            let total = total.min(1.0);
            for k in 0..3 {
                let v = rgb[k] + (1.0 - total) * bg[k];
                let noise = (hash(x as i64, y as i64, 21 + k as u64) - 0.5) * 0.05;
                out[4 * i + k] = ((v + noise).clamp(0.0, 1.0) * 255.0).round() as u8;
            }
        }
    }
    Ok(out)
}

/// The mask a user's photo gives: the photo through [`segment::segment_auto_with`] with the
/// building's options, as the CLI does for `--generator building` (the automatic cut,
/// [`segment::Segmentation::mask`]).
pub fn segmented(view: &View, rgba: &[u8]) -> Result<Mask, FitError> {
    Ok(segment_photo(view, rgba)?.1.mask)
}

/// The photo as the segmentation reads it and its automatic cut.
fn segment_photo(view: &View, rgba: &[u8]) -> Result<(Photo, segment::Segmentation), FitError> {
    let e = |x: segment::SegmentError| FitError(x.0);
    let p = Photo::from_rgba(view.width, view.height, rgba, segment::WORKING_SIDE).map_err(e)?;
    let opts = segment::Options::for_generator(Some(&crate::generators::building::Building));
    let seg = segment::segment_auto_with(&p, &opts).map_err(e)?;
    Ok((p, seg))
}

/// The mask of one input of a case: the clean silhouette or a segmented photo.
pub fn input_mask(mesh: &Mesh, view: &View, input: Input) -> Result<Mask, FitError> {
    match input {
        Input::Mask => true_mask(mesh, view),
        _ => segmented(view, &photo(mesh, view, input)?),
    }
}

/// One run of a fit's restarts ([`BenchScore::runs`]): what it found and how it scores.
#[derive(Clone, Debug)]
pub struct RunScore {
    /// Its final loss.
    pub loss: f64,
    /// Its [`Generator::tie_prior`].
    pub tie_prior: f64,
    /// The paper's IoU-64 against the truth, as [`BenchScore::iou64`].
    pub iou64: f64,
    /// Its IoU-64 against the kept run's model, both in the kept run's frame
    /// ([`eval::fit_agreement`]): how different a shape it is.
    pub agreement: f64,
    /// Its photo-view IoU against the mask the fit was given, as
    /// [`BenchScore::mask_photo_iou`].
    pub photo_iou: f64,
    /// Whether the fit kept this run.
    pub kept: bool,
    /// Its main shape parameters, `name=value` separated by spaces.
    pub shape: String,
}

/// The scores of one fit.
#[derive(Clone, Debug)]
pub struct BenchScore {
    /// The paper's IoU-64 against the truth (128², the fit at HIGH in the truth's frame).
    pub iou64: f64,
    /// The fit through its own fitted camera against the true mask.
    pub photo_iou: f64,
    /// The fit through its own fitted camera against the mask it was given (a photo's
    /// automatic cut), as the CLI prints it ([`eval::result_photo_ious`]): what the user sees.
    pub mask_photo_iou: f64,
    /// For a photo: CIE76 ΔE*ab of the fitted model's wall and roof colours measured in the
    /// photo ([`crate::colors::estimate`]) against the colours the photo was drawn with
    /// (`None` where the fitted model has no such part in view).
    pub colour_de: Option<(Option<f64>, Option<f64>)>,
    /// How well the mask fixes the shape, as the CLI prints it ([`Session::agreement`]).
    pub agreement: Option<f64>,
    /// Whether the photo shows the kept model only from the front ([`Session::front_only`]).
    pub front_only: bool,
    /// Every run of the fit, when asked for ([`BenchFit::each`]); empty otherwise.
    pub runs: Vec<RunScore>,
    /// With window labels: whether the fit left them out ([`Session::windows_left_out`]).
    pub windows_left_out: bool,
    /// With window labels and [`BenchFit::each`]: the two runs the fit chose between
    /// ([`Session::window_candidates`]), the one fitting the labels first, each as its
    /// photo-view IoU against the mask the fit was given and its IoU-64.
    pub window_candidates: Option<[(f64, f64); 2]>,
}

/// Fits `mask` as the CLI does with the building generator (the field of view known) with the
/// budget and seed of `fit`, and scores it against `truth` seen through `view`; with
/// `fit.each`, every run of the fit too ([`BenchScore::runs`]).
pub fn fit_and_score(
    truth: &Mesh,
    view: &View,
    mask: Mask,
    fit: BenchFit,
) -> Result<BenchScore, FitError> {
    fit_scored(truth, view, mask, None, None, fit)
}

/// [`fit_and_score`] from `input` made of `truth` through `view` ([`input_mask`]), and for a
/// photo also the part colours measured in it ([`BenchScore::colour_de`]); with
/// `fit.windows`, a photo is fitted with the window labels found in it too.
pub fn fit_and_score_input(
    truth: &Mesh,
    view: &View,
    input: Input,
    fit: BenchFit,
) -> Result<BenchScore, FitError> {
    if input == Input::Mask {
        return fit_and_score(truth, view, true_mask(truth, view)?, fit);
    }
    let px = photo(truth, view, input)?;
    let (p, seg) = segment_photo(view, &px)?;
    // The windows the page's "Find windows" finds, within the same cut.
    let windows = match fit.windows {
        true => Some(segment::windows::detect_windows(&p, &seg).map_err(|x| FitError(x.0))?),
        false => None,
    };
    fit_scored(truth, view, seg.mask, Some(&px), windows, fit)
}

fn fit_scored(
    truth: &Mesh,
    view: &View,
    mask: Mask,
    photo: Option<&[u8]>,
    windows: Option<LabelImage>,
    fit: BenchFit,
) -> Result<BenchScore, FitError> {
    let for_colours = mask.clone();
    let generator = crate::generators::building::Building.name();
    let mut config = FitConfig {
        generator: generator.into(),
        fov_y: vec![Some(view.params.fov_y)],
        quality: fit.quality,
        restarts: fit.runs_for(generator),
        seed: fit.seed,
        ..FitConfig::default()
    };
    if let Some(w) = windows {
        config.windows = vec![Some(w)];
    }
    let mut session = Session::new(config, vec![mask])?;
    let result = session.run()?;
    let agreement = session.agreement()?;
    let front_only = session.front_only()?;
    let (iou, mesh) = fit_iou64(&result, truth, view)?;
    let fitted = result
        .views
        .first()
        .ok_or_else(|| FitError("a fit without a view".into()))?;
    let mut runs = Vec::new();
    if fit.each {
        for run in session.run_results().into_iter().flatten() {
            let p = &run.model.params;
            let shape = [
                ("floors", idx::FLOORS),
                ("depth", idx::DEPTH),
                ("floor_h", idx::FLOOR_HEIGHT),
                ("roof", idx::ROOF_TYPE),
                ("pitch", idx::ROOF_PITCH),
                ("overhang", idx::ROOF_OVERHANG),
                ("footprint", idx::FOOTPRINT),
                ("wing", idx::WING_LENGTH),
                ("wing_w", idx::WING_WIDTH),
                ("balcony_start", idx::BALCONY_START),
                ("chimneys", idx::CHIMNEYS),
                ("chimney_h", idx::CHIMNEY_HEIGHT),
                ("hip_ridge", idx::HIP_RIDGE),
            ]
            .iter()
            .map(|(n, i)| format!("{n}={:.2}", p[*i]))
            .collect::<Vec<_>>()
            .join(" ");
            // The model's bounding box, width × depth × height over its height.
            let built = run
                .model
                .generator
                .generate(p, run.model.lod)
                .map_err(|e| FitError(e.to_string()))?;
            let shape = match built.bounds() {
                Some((lo, hi)) => {
                    let d = hi - lo;
                    format!("box={:.2}x{:.2}x1 {shape}", d.x / d.y, d.z / d.y)
                }
                None => shape,
            };
            runs.push(RunScore {
                loss: run.loss,
                tie_prior: run.model.generator.tie_prior(p),
                iou64: fit_iou64(run, truth, view)?.0,
                agreement: eval::fit_agreement(&result, run, 128)?,
                photo_iou: eval::result_photo_ious(run, std::slice::from_ref(&for_colours))?[0],
                kept: run.loss == result.loss && *p == result.model.params,
                shape,
            });
        }
    }
    let photo_iou = view_iou(&mesh, fitted, &true_mask(truth, view)?)?;
    let mask_photo_iou = eval::result_photo_ious(&result, std::slice::from_ref(&for_colours))?
        .first()
        .copied()
        .ok_or_else(|| FitError("a fit without a view".into()))?;
    let colour_de = match photo {
        None => None,
        Some(px) => {
            let rgba = crate::colors::Rgba {
                width: view.width,
                height: view.height,
                pixels: px,
            };
            let found = crate::colors::estimate(&mesh, &[*fitted], &[rgba], &[for_colours])
                .map_err(|e| FitError(e.0))?;
            let de = |part: &str, truth: u8| {
                let want = COLOURS[usize::from(truth)].map(crate::colors::srgb_to_linear);
                found
                    .iter()
                    .find(|c| c.part == part && c.source != crate::colors::Source::Default)
                    .map(|c| crate::colors::delta_e76(c.color, want))
            };
            Some((de("wall", WALL), de("roof", ROOF)))
        }
    };
    Ok(BenchScore {
        iou64: iou,
        photo_iou,
        mask_photo_iou,
        colour_de,
        agreement,
        front_only,
        runs,
        windows_left_out: session.windows_left_out().is_some(),
        window_candidates: match (session.window_candidates(), fit.each) {
            (Some([(f, a), (p, b)]), true) => {
                let results = session.run_results();
                let iou = |k: usize| -> Result<f64, FitError> {
                    let run = results[k].ok_or_else(|| FitError("an unfinished run".into()))?;
                    Ok(fit_iou64(run, truth, view)?.0)
                };
                Some([(a, iou(f)?), (b, iou(p)?)])
            }
            _ => None,
        },
    })
}

/// The paper's IoU-64 of `fit` against `truth` (the fit moved into the truth's frame through
/// `view`, 128²), and the fitted mesh.
fn fit_iou64(fit: &FitResult, truth: &Mesh, view: &View) -> Result<(f64, Mesh), FitError> {
    let mesh = fit
        .model
        .generator
        .generate(&fit.model.params, Lod::High)
        .map_err(|e| FitError(e.to_string()))?;
    let fitted = fit
        .views
        .first()
        .ok_or_else(|| FitError("a fit without a view".into()))?;
    let aligned = align_to_reference(&mesh.positions, &fitted.params, &view.params);
    let iou = iou64(
        (&aligned, &mesh.triangles),
        (&truth.positions, &truth.triangles),
        128,
    )?;
    Ok((iou, mesh))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cases_are_closed_and_outward() {
        for c in cases().unwrap() {
            // Every edge is shared by exactly two triangles in opposite directions.
            let mut edges = std::collections::HashMap::new();
            for t in &c.mesh.triangles {
                for k in 0..3 {
                    *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
                }
            }
            for (&(a, b), &n) in &edges {
                assert_eq!(n, 1, "{}: edge {a}-{b} used {n} times", c.name);
                assert_eq!(edges.get(&(b, a)), Some(&1), "{}: open edge", c.name);
            }
            // Outward: the signed volume is positive.
            let vol: f32 = c
                .mesh
                .triangles
                .iter()
                .map(|t| {
                    let [a, b, cc] = t.map(|i| c.mesh.positions[i as usize]);
                    a.dot(b.cross(cc)) / 6.0
                })
                .sum();
            assert!(vol > 0.0, "{}: volume {vol}", c.name);
            c.mesh.check().unwrap();
        }
    }
}
