//! GrabCut-style segmentation (Rother, Kolmogorov & Blake 2004): colour mixtures for object and
//! background, a contrast-sensitive smoothness term, and an exact min-cut, iterated.
//!
//! A [`Session`] owns everything a re-cut needs (colours, n-link weights, colour models, the
//! user's hard constraints, the graph's buffers), so an interactive edit — a rectangle or a
//! stroke — costs [`Options::recut_iterations`] colour fits and cuts starting from the previous
//! labelling, not a new segmentation (the max-flow itself restarts from zero flow).
//!
//! Automatic mode replaces GrabCut's user rectangle by a background model learnt from the image
//! border. The object may touch one border (it stands on a table or the floor): each side of the
//! border is tested against a model of the other three, and a side whose colours the others do
//! not explain gets no hard background constraint and lends only its explained pixels to the
//! border model. Pixels whose colour the border model does not explain start as object.
//!
//! Automatic mode runs coarse to fine: the photo is first segmented at half size (recursively,
//! down to ~160×120), and the full-size cuts then only relabel a band of six pixels around
//! the upsampled outline — the expensive part of a cut is settling the whole image, which the
//! small image does cheaply.
//!
//! Clean-up keeps the largest 8-connected component (plus any component the user marked as
//! object) and fills holes, except holes whose colours the border model explains (the loop of
//! a handle shows the background) and holes the user marked as background.
//!
//! Everything is deterministic (no random seeds, no clock), so tests and the page agree.

use super::decode::area_resample;
use super::gmm::{Gmm, Rgb};
use super::maxflow::Graph;
use super::morph;
use super::plausible::doubt as plausible_doubt;
use super::{BBox, Label, Photo, SegmentError, Segmentation, Stroke};
use crate::mask::Mask;

/// Photos with at least this many pixels are first segmented at half size (coarse to fine);
/// the half-size image then has at least 160×120 pixels.
const COARSE_MIN_PIXELS: usize = 4 * 160 * 120;
/// Half-width of the band around the coarse outline that full-size cuts may relabel.
const BAND: usize = 6;
/// Smoothness weight γ of GrabCut's energy (eq. 11; the paper's value).
const GAMMA: f32 = 50.0;
/// The last cut's smoothness by default, as a share of GrabCut's γ (the cut near the outline
/// that ends each segmentation, [`Options::outline_smoothing`]).
pub const OUTLINE_SMOOTHING: f32 = 0.5;
/// How far (pixels) from the outline the last cut may move it.
const OUTLINE_BAND: usize = 6;
/// Capacity of a hard constraint: larger than any cut through a pixel's eight n-links.
pub(super) const HARD: f32 = 1.0e6;
/// Largest number of samples used to fit one colour model (the rest adds time, not accuracy).
const MAX_SAMPLES: usize = 12_000;
/// Fraction of a border side's pixels that the other sides must fail to explain for the side to
/// count as touched by the object.
const TOUCH_FRACTION: f32 = 0.12;
/// Percentile of the border pixels' own negative log-likelihood above which a pixel's colour is
/// "not seen on the border".
const BORDER_PERCENTILE: f32 = 0.97;

/// Radius of the opening that cleans the first object seed (pixels the border does not
/// explain) of streaks and specks, in pixels of the coarsest image.
const SEED_OPENING: usize = 1;

/// Brightness factors by which the border's colours may appear elsewhere in the background: a
/// soft shadow darkens a table to about half, a table darkens or brightens away from or
/// towards the light (see [`Gmm::nll_shaded`]).
const SHADE_RANGE: [f32; 2] = [0.4, 1.25];

/// Extra negative log-likelihood allowed when deciding that a colour matches a stroke's.
const STROKE_MARGIN: f32 = 6.0;

const NONE: u8 = 0;
const HARD_FG: u8 = 1;
const HARD_BG: u8 = 2;
/// Background painted by a correcting user stroke: a statement about its colour too (see
/// [`Session::add_stroke`]).
const STROKE_BG: u8 = 3;
/// Background painted by a user stroke that only fixes its own pixels.
const PAINT_BG: u8 = 4;
/// Object painted by a correcting user stroke (colour semantics, like [`STROKE_BG`]).
const STROKE_FG: u8 = 5;
/// Share of a stroke's pixels that must have had the opposite label for the stroke to count
/// as a correction of a colour rather than a touch-up of pixels.
const CORRECTION_SHARE: f32 = 0.8;

fn is_bg(h: u8) -> bool {
    h == HARD_BG || h == STROKE_BG || h == PAINT_BG
}

fn is_fg(h: u8) -> bool {
    h == HARD_FG || h == STROKE_FG
}

/// Options of automatic segmentation.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// GrabCut iterations (colour refit + cut) in automatic mode.
    pub iterations: usize,
    /// Iterations per interactive re-cut.
    pub recut_iterations: usize,
    /// The smoothness of the last cut, near the outline, as a share of GrabCut's (in (0, 1];
    /// lower lets the colours carry the outline further into a corner): the object kind's
    /// ([`Capabilities::outline_smoothing`](crate::generators::Capabilities::outline_smoothing)),
    /// [`OUTLINE_SMOOTHING`] when the kind is not known.
    pub outline_smoothing: f32,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            iterations: 4,
            recut_iterations: 2,
            outline_smoothing: OUTLINE_SMOOTHING,
        }
    }
}

impl Options {
    /// The default options with the outline smoothing of `generator`, or the default's when
    /// it is `None` (the object kind is chosen later, as `reconstruct --generator auto` does).
    pub fn for_generator(generator: Option<&dyn crate::generators::Generator>) -> Options {
        Options {
            outline_smoothing: generator
                .map_or(OUTLINE_SMOOTHING, |g| g.capabilities().outline_smoothing),
            ..Options::default()
        }
    }
}

/// An automatic or interactive segmentation of one photo, kept for re-cuts.
#[derive(Clone, Debug)]
pub struct Session {
    w: usize,
    h: usize,
    opts: Options,
    colors: Vec<Rgb>,
    /// Smoothness weights to the right, down, down-right and down-left neighbours (eq. 11).
    nlinks: Vec<[f32; 4]>,
    /// The colour model of the image's border (the background's colours).
    border_model: Gmm,
    /// Border NLL above which a colour is "not background-like".
    border_tau: f32,
    /// Sides (top, bottom, left, right) whose colours the other sides do not explain. Read only
    /// by [`Session::automatic`], which keeps the outermost ring of every other side, and of
    /// every side the frame check finds nothing running off, as hard background.
    touched: [bool; 4],
    /// Sides the object seems to run off, from the photo's colours (see `frame`); `None` once
    /// the user has said where the object is (a rectangle, a stroke) or outside automatic mode.
    crossed: Option<[bool; 4]>,
    fg: Option<Gmm>,
    bg: Option<Gmm>,
    hard: Vec<u8>,
    labels: Vec<bool>,
    dfg: Vec<f32>,
    dbg: Vec<f32>,
    graph: Graph,
    result: Segmentation,
}

impl Session {
    /// Automatic segmentation: border background model, then GrabCut iterations.
    pub fn automatic(photo: &Photo, opts: &Options) -> Result<Session, SegmentError> {
        let mut s = Session::prepare(photo, opts)?;
        let crossed = super::frame::crossed_sides(&s.colors, s.w, s.h);
        s.crossed = Some(crossed);
        // A side the others' colours do not explain may still be background: a wall lit warm
        // from one side and cool from the other, darker towards the floor, differs on every
        // side. The frame check follows each side along its length: where it finds no object
        // running off, the side is background whatever the others look like.
        for (t, c) in s.touched.iter_mut().zip(crossed) {
            *t &= c;
        }
        // Hard background: the outermost ring on the sides the object does not touch.
        let (w, h) = (s.w, s.h);
        for x in 0..w {
            if !s.touched[0] {
                s.hard[x] = HARD_BG;
            }
            if !s.touched[1] {
                s.hard[(h - 1) * w + x] = HARD_BG;
            }
        }
        for y in 0..h {
            if !s.touched[2] {
                s.hard[y * w] = HARD_BG;
            }
            if !s.touched[3] {
                s.hard[y * w + w - 1] = HARD_BG;
            }
        }
        let start = coarse_labels(photo, opts)?;
        let coarse = start.is_some();
        s.labels = match start {
            // Coarse to fine: the half-size result starts the fit here, so the full-size cuts
            // only move the outline (cheap) instead of settling the whole image (costly).
            Some(coarse) => (0..w * h).map(|i| !is_bg(s.hard[i]) && coarse[i]).collect(),
            None => {
                let tau = s.border_tau;
                let unexplained: Vec<bool> = (0..w * h)
                    .map(|i| !is_bg(s.hard[i]) && s.border_nll(i) > tau)
                    .collect();
                // A table's grain and a background's odd pixel are streaks and specks that the
                // border happened not to show; an object is a region. Left in, they teach the
                // object's colour model the background's colours.
                morph::open(&unexplained, w, h, SEED_OPENING)
            }
        };
        let iterations = s.opts.iterations;
        s.run(iterations, true, coarse)?;
        Ok(s)
    }

    /// Interactive start from a rectangle (GrabCut proper): outside is background for sure,
    /// inside starts as object.
    pub fn with_rect(photo: &Photo, rect: BBox, opts: &Options) -> Result<Session, SegmentError> {
        let mut s = Session::prepare(photo, opts)?;
        s.set_rect(rect)?;
        s.labels = (0..s.w * s.h).map(|i| !is_bg(s.hard[i])).collect();
        let iterations = s.opts.iterations;
        s.run(iterations, true, false)?;
        Ok(s)
    }

    /// Marks everything outside `rect` (working-image pixels, end exclusive) as background.
    pub fn set_rect(&mut self, rect: BBox) -> Result<(), SegmentError> {
        if rect.x0 >= rect.x1
            || rect.y0 >= rect.y1
            || rect.x1 as usize > self.w
            || rect.y1 as usize > self.h
        {
            return Err(SegmentError(format!(
                "rectangle {rect:?} is empty or outside the {}×{} image",
                self.w, self.h
            )));
        }
        for y in 0..self.h {
            for x in 0..self.w {
                let inside = (rect.x0 as usize..rect.x1 as usize).contains(&x)
                    && (rect.y0 as usize..rect.y1 as usize).contains(&y);
                let i = y * self.w + x;
                if !inside {
                    self.hard[i] = HARD_BG;
                    self.labels[i] = false;
                } else if self.hard[i] == HARD_BG {
                    self.hard[i] = NONE;
                }
            }
        }
        Ok(())
    }

    /// Paints a stroke of hard constraints (object or background) along a polyline.
    ///
    /// A stroke lying mostly (≥ 80 %) on pixels that had the other label is a correction and
    /// also speaks for its colours: "this stuff is background" removes the stroke's colours from
    /// the object's colour model (and vice versa), so a whole wrongly included region goes with
    /// one stroke. A stroke that straddles the outline (a touch-up, or a sloppy one) only fixes
    /// its own pixels, so it cannot flood the image.
    pub fn add_stroke(&mut self, stroke: &Stroke) -> Result<(), SegmentError> {
        let (w, h) = (self.w, self.h);
        let mut pixels = Vec::new();
        for_stroke_pixels(stroke, w, h, |i| pixels.push(i))?;
        // The user now says where the object is: the automatic mask's doubt about the frame
        // no longer applies.
        self.crossed = None;
        let object = stroke.label == Label::Object;
        let opposite = pixels.iter().filter(|&&i| self.labels[i] != object).count();
        let correction = opposite as f32 >= CORRECTION_SHARE * pixels.len() as f32;
        let value = match (object, correction) {
            (true, true) => STROKE_FG,
            (true, false) => HARD_FG,
            (false, true) => STROKE_BG,
            (false, false) => PAINT_BG,
        };
        for i in pixels {
            self.hard[i] = value;
            self.labels[i] = object;
        }
        Ok(())
    }

    /// Forgets every stroke (the rectangle or border constraints stay); call
    /// [`Session::recut`] afterwards.
    pub fn clear_strokes(&mut self) {
        for h in &mut self.hard {
            if *h != HARD_BG {
                *h = NONE;
            }
        }
    }

    /// Re-runs the cut after rectangles or strokes changed: fits the colour models to the
    /// current labelling and the strokes, and cuts, `recut_iterations` times.
    pub fn recut(&mut self) -> Result<&Segmentation, SegmentError> {
        let iterations = self.opts.recut_iterations.max(1);
        // Fresh fits: a stroke can remove a colour from a model entirely, which a refit of the
        // old components (one of them fitted to that colour) would not do.
        self.run(iterations, true, false)?;
        Ok(&self.result)
    }

    /// The current result.
    pub fn segmentation(&self) -> &Segmentation {
        &self.result
    }

    fn prepare(photo: &Photo, opts: &Options) -> Result<Session, SegmentError> {
        let (w, h) = (photo.width() as usize, photo.height() as usize);
        if w < 8 || h < 8 {
            return Err(SegmentError(format!("{w}×{h} is too small to segment")));
        }
        if opts.iterations == 0 {
            return Err(SegmentError::new(
                "at least one GrabCut iteration is needed",
            ));
        }
        if !(opts.outline_smoothing > 0.0 && opts.outline_smoothing <= 1.0) {
            return Err(SegmentError(format!(
                "the outline smoothing must be in (0, 1], not {}",
                opts.outline_smoothing
            )));
        }
        let colors = photo.colors();
        let nlinks = nlinks_of(&colors, w, h);
        let (border_model, border_tau, touched) = border_model(&colors, w, h)?;
        let empty = Mask::empty(w as u32, h as u32)?;
        Ok(Session {
            w,
            h,
            opts: opts.clone(),
            nlinks,
            border_model,
            border_tau,
            touched,
            crossed: None,
            fg: None,
            bg: None,
            hard: vec![NONE; w * h],
            labels: vec![false; w * h],
            dfg: vec![0.0; w * h],
            dbg: vec![0.0; w * h],
            graph: Graph::default(),
            result: Segmentation {
                object: empty.clone(),
                mask: empty,
                bbox: None,
                confidence: 0.0,
                warnings: Vec::new(),
            },
            colors,
        })
    }

    /// Colour-model fits and cuts; with `fresh` the first fit starts from k-means instead of the
    /// previous models (later ones always refine the previous models, as GrabCut does).
    ///
    /// With `band`, each cut only relabels pixels within [`BAND`] of the current outline (the
    /// outline came from the half-size result, so it is off by a pixel or two at most).
    fn run(&mut self, iterations: usize, fresh: bool, band: bool) -> Result<(), SegmentError> {
        let n = self.w * self.h;
        let min_object = (n / 2000).max(4);
        for it in 0..iterations {
            let hard = &self.hard;
            let fit_labels =
                morph::largest_component(&self.labels, self.w, self.h, &|i| is_fg(hard[i]));
            let fg_count = fit_labels.iter().filter(|&&l| l).count();
            if fg_count < min_object {
                self.labels = fit_labels;
                break;
            }
            self.fit_models(&fit_labels, fresh && it == 0)?;
            let changed = if band {
                let active = morph::boundary_band(&fit_labels, self.w, self.h, BAND);
                self.labels = fit_labels;
                self.cut_band(&active)
            } else {
                self.cut()
            };
            // Converged: another colour fit would reproduce the same cut.
            if changed <= n / 2000 {
                break;
            }
        }
        self.finish()?;
        self.refine_outline();
        self.finish()
    }

    /// One more cut near the outline (within [`OUTLINE_BAND`]) with the smoothness term at
    /// [`Options::outline_smoothing`] of its weight ([`OUTLINE_SMOOTHING`] by default). At full
    /// weight the cut takes a short path along a strong edge inside the object when a thin
    /// strip of it is close in colour to what lies beyond: a building's wall below its lowest
    /// windows or beside its last column of them, in shade, against grass, was cut off along
    /// the windows' edges. The first cuts, at full weight, still decide what the object is (a
    /// spoon beside a saucer stays out: a band cannot reach it).
    ///
    /// On the independent building benchmark's photos the automatic masks' mean IoU went
    /// 0.988 → 0.991 (the five-storey block on the gradient 0.958 → 0.974), and the fits'
    /// IoU-64 (`cargo bench --bench building_bench -- --seed N`, seeds 0 / 1 / 2) on the
    /// gradient 0.890 / 0.877 / 0.899 → 0.916 / 0.904 / 0.917, on textured ground 0.886 /
    /// 0.880 / 0.887 → 0.918 / 0.875 / 0.910; on plain ground, whose masks moved by 0.001 at
    /// most, 0.942 / 0.945 / 0.946 → 0.926 / 0.938 / 0.938 (how much a fit moves when its
    /// mask moves by a pixel here and there). The Mitsuba dish photos (`cargo bench --bench
    /// dish_photo_bench -- --fov known --seed N`): masks 0.978 either way, IoU-64 0.921 /
    /// 0.916 / 0.920 → 0.922 / 0.922 / 0.922. At 0.3 of the weight the buildings gain more
    /// (gradient 0.924 / 0.926 / 0.914, textured 0.901 / 0.923 / 0.922) and the dishes lose
    /// (0.908 / 0.906 / 0.914: the vase's mask 0.975 → 0.966); at 0.4 the buildings score as
    /// here and the dishes as at 0.3 (0.910 / 0.910 / 0.907). So the weight is the object
    /// kind's ([`Options::outline_smoothing`]): 0.1 for a building (measured against 0.3 and
    /// 0.2 in the building generator's capabilities), 0.5 for the rest.
    ///
    /// Tried for one weight for all and not kept: a second pass over a band around the new
    /// outline, or a wider band (12 pixels), changed no building photo's mask (the band is not
    /// what stops the cut, the smoothness is); the smoothness weights from the photo blurred
    /// 3×3 (the grain of grass or cobbles is finer than an outline) lowered the building
    /// photos' mean mask IoU 0.991 → 0.985 (all cuts) or 0.988 (the last); choosing per photo
    /// the weight (0.5 or 0.3) whose outline follows the photo's edges more
    /// ([`super::plausible`]'s edge support) chose 0.5 where 0.3 was right (the L with flat
    /// roofs on textured ground: edge support 0.84 at 0.5, 0.75 at 0.3, mask IoU 0.974 and
    /// 0.991: a finer cut follows the grass's grain too).
    fn refine_outline(&mut self) {
        let active = morph::boundary_band(&self.labels, self.w, self.h, OUTLINE_BAND);
        let full = std::mem::take(&mut self.nlinks);
        self.nlinks = full
            .iter()
            .map(|l| l.map(|v| v * self.opts.outline_smoothing))
            .collect();
        self.cut_band(&active);
        self.nlinks = full;
    }

    fn fit_models(&mut self, labels: &[bool], fresh: bool) -> Result<(), SegmentError> {
        // Colours the user marked as background are no evidence for the object, and vice
        // versa: a stroke means "this colour belongs there", not only "these pixels".
        let exclude_fg = stroke_colour_filter(&self.colors, &self.hard, STROKE_BG);
        let exclude_bg = stroke_colour_filter(&self.colors, &self.hard, STROKE_FG);
        let mut fg_s = Vec::new();
        let mut bg_s = Vec::new();
        let n = labels.len();
        let stride = (n / MAX_SAMPLES).max(1);
        for i in (0..n).step_by(stride) {
            let c = &self.colors[i];
            let object = match self.hard[i] {
                h if is_fg(h) => true,
                h if is_bg(h) => false,
                _ => labels[i],
            };
            if object {
                if is_fg(self.hard[i]) || !exclude_fg.as_ref().is_some_and(|f| f(c)) {
                    fg_s.push(*c);
                }
            } else if is_bg(self.hard[i]) || !exclude_bg.as_ref().is_some_and(|f| f(c)) {
                bg_s.push(*c);
            }
        }
        // Strokes are thin; without this the sampling stride could skip all of them.
        for i in 0..n {
            if i % stride != 0 {
                match self.hard[i] {
                    h if is_fg(h) && fg_s.len() < 2 * MAX_SAMPLES => fg_s.push(self.colors[i]),
                    h if is_bg(h) && bg_s.len() < 2 * MAX_SAMPLES && i % 4 == 0 => {
                        bg_s.push(self.colors[i])
                    }
                    _ => {}
                }
            }
        }
        // A thin object (a seed cleaned down to a strip) can fall between the sampling
        // stride's columns: then every one of its pixels is a sample.
        if fg_s.is_empty() {
            fg_s.extend(
                (0..n)
                    .filter(|&i| !is_bg(self.hard[i]) && (is_fg(self.hard[i]) || labels[i]))
                    .take(MAX_SAMPLES)
                    .map(|i| self.colors[i]),
            );
        }

        let refit = |old: &Option<Gmm>, s: &[Rgb]| match old {
            Some(g) if !fresh => g.refit(s).or_else(|| Gmm::fit(s, 2)),
            _ => Gmm::fit(s, 2),
        };
        let fg = refit(&self.fg, &fg_s);
        let bg = refit(&self.bg, &bg_s);
        match (fg, bg) {
            (Some(f), Some(b)) => {
                self.fg = Some(f);
                self.bg = Some(b);
                Ok(())
            }
            _ => Err(SegmentError::new(
                "cannot build colour models: no object or no background pixels",
            )),
        }
    }

    /// One min-cut of GrabCut's energy with the current colour models (eq. 7–11).
    /// Returns how many pixels changed label.
    fn cut(&mut self) -> usize {
        let (Some(fg), Some(bg)) = (&self.fg, &self.bg) else {
            return 0;
        };
        let (w, h) = (self.w, self.h);
        for (i, c) in self.colors.iter().enumerate() {
            self.dfg[i] = fg.nll(c);
            self.dbg[i] = bg.nll(c);
        }

        let (hard, dfg, dbg) = (&self.hard, &self.dfg, &self.dbg);
        let g = &mut self.graph;
        cut_grid(g, w, h, &self.nlinks, true, |i| match hard[i] {
            h if is_fg(h) => HARD,
            h if is_bg(h) => -HARD,
            // Only the difference of the data terms matters to the cut.
            _ => dbg[i] - dfg[i],
        });
        let mut changed = 0;
        for i in 0..w * h {
            let l = g.is_source(i);
            changed += usize::from(l != self.labels[i]);
            self.labels[i] = l;
        }
        changed
    }

    /// A cut restricted to the `active` pixels; the others keep their labels and act on their
    /// active neighbours through the n-links, as terminal links. Returns the changed count.
    fn cut_band(&mut self, active: &[bool]) -> usize {
        let (Some(fg), Some(bg)) = (&self.fg, &self.bg) else {
            return 0;
        };
        let (w, h) = (self.w, self.h);
        for (i, c) in self.colors.iter().enumerate() {
            self.dfg[i] = fg.nll(c);
            self.dbg[i] = bg.nll(c);
        }
        let mut node = vec![u32::MAX; w * h];
        let mut pixels = Vec::new();
        for (i, _) in active.iter().enumerate().filter(|(_, a)| **a) {
            node[i] = pixels.len() as u32;
            pixels.push(i);
        }
        let g = &mut self.graph;
        g.reset(pixels.len(), 4 * pixels.len());
        // Neighbour offsets with the index of their weight in `nlinks` (of the upper-left pixel
        // of the pair, which stores it).
        let dirs: [(isize, isize, usize); 8] = [
            (1, 0, 0),
            (0, 1, 1),
            (1, 1, 2),
            (-1, 1, 3),
            (-1, 0, 0),
            (0, -1, 1),
            (-1, -1, 2),
            (1, -1, 3),
        ];
        for (k, &i) in pixels.iter().enumerate() {
            let mut d = match self.hard[i] {
                h if is_fg(h) => HARD,
                h if is_bg(h) => -HARD,
                _ => self.dbg[i] - self.dfg[i],
            };
            let (x, y) = ((i % w) as isize, (i / w) as isize);
            for (n, &(dx, dy, slot)) in dirs.iter().enumerate() {
                let (nx, ny) = (x + dx, y + dy);
                if nx < 0 || ny < 0 || nx >= w as isize || ny >= h as isize {
                    continue;
                }
                let j = ny as usize * w + nx as usize;
                let wgt = if n < 4 {
                    self.nlinks[i][slot]
                } else {
                    self.nlinks[j][slot]
                };
                if node[j] == u32::MAX {
                    // A fixed neighbour pulls towards its own label.
                    d += if self.labels[j] { wgt } else { -wgt };
                } else if n < 4 {
                    g.add_edge(k, node[j] as usize, wgt, wgt);
                }
            }
            let d = d.clamp(-HARD, HARD);
            if d > 0.0 {
                g.add_tweights(k, d, 0.0);
            } else {
                g.add_tweights(k, 0.0, -d);
            }
        }
        g.maxflow();
        let mut changed = 0;
        for (k, &i) in pixels.iter().enumerate() {
            let l = g.is_source(k);
            changed += usize::from(l != self.labels[i]);
            self.labels[i] = l;
        }
        changed
    }

    /// Negative log-likelihood of pixel `i` under the border model, shaded copies of its
    /// colours included ([`Gmm::nll_shaded`]). Computed where asked, not for every pixel: with a
    /// coarse start only the hole test needs it, on a few pixels.
    fn border_nll(&self, i: usize) -> f32 {
        self.border_model
            .nll_shaded(&self.colors[i], SHADE_RANGE[0], SHADE_RANGE[1])
    }

    /// Clean-up (largest component, holes), bounding box and confidence.
    fn finish(&mut self) -> Result<(), SegmentError> {
        let (w, h) = (self.w, self.h);
        let n = w * h;
        let hard = &self.hard;
        let mut obj = morph::largest_component(&self.labels, w, h, &|i| is_fg(hard[i]));
        // Fill holes unless they are real: a hole whose colours match the border background
        // (a handle's loop) or that the user marked as background stays open.
        let min_hole = (n / 4000).max(6);
        for hole in morph::holes(&obj, w, h) {
            let marked = hole
                .iter()
                .any(|&i| self.hard[i] == STROKE_BG || self.hard[i] == PAINT_BG);
            let bg_like = hole
                .iter()
                .filter(|&&i| self.border_nll(i) <= self.border_tau)
                .count();
            let real = marked || (hole.len() >= min_hole && 2 * bg_like >= hole.len());
            if !real {
                for i in hole {
                    obj[i] = true;
                }
            }
        }
        let area = obj.iter().filter(|&&o| o).count();
        let mut warnings = Vec::new();
        let frac = area as f32 / n as f32;
        if frac < 0.002 {
            warnings.push(
                "no distinct object found: the whole image looks like its border \
                 (a uniform image, or an object filling the frame)"
                    .to_owned(),
            );
        } else if frac < super::SMALL_MASK {
            warnings.push(format!(
                "the object covers only {:.1} % of the photo: if it is bigger than the mask, \
                 draw a box around it or paint it with the object brush",
                100.0 * frac
            ));
        } else if frac > 0.9 {
            warnings.push("the object seems to fill the whole frame".to_owned());
        }
        let sides = touching_sides(&obj, w, h);
        if area > 0 && sides >= 2 {
            warnings.push(format!(
                "the object touches {sides} image borders; the background model may be wrong"
            ));
        }
        // Sides of the border that differ from each other (a table's far end darker than its
        // near end) are no sign of a wrong mask by themselves: the frame check looks along
        // each side for an object running off it. A box or strokes say where the object is.
        if let Some(w) = self.crossed.and_then(|c| frame_warning(&c, &obj, w, h)) {
            warnings.push(w);
        }
        // The cut's own colour models vouch for a mask that took in table: judge it against
        // the photo around it instead. Only for the automatic mask; a mask the user has
        // edited is theirs.
        if self.crossed.is_some()
            && warnings.is_empty()
            && let Some(doubt) =
                super::plausible::assess(&self.colors, &obj, w, h).and_then(|p| plausible_doubt(&p))
        {
            warnings.push(doubt);
        }
        // Confidence: how often the cut agrees with the colour models alone, near the object
        // (its box grown by half its size on each side), object and background pixels weighted
        // equally — so a large, easy background cannot vouch for a doubtful outline.
        let agree = match (self.fg.is_some(), bbox_of(&obj, w)) {
            (true, Some(b)) => {
                let (bw, bh) = ((b.x1 - b.x0) as usize, (b.y1 - b.y0) as usize);
                let (x0, x1) = (
                    (b.x0 as usize).saturating_sub(bw / 2),
                    (b.x1 as usize + bw / 2).min(w),
                );
                let (y0, y1) = (
                    (b.y0 as usize).saturating_sub(bh / 2),
                    (b.y1 as usize + bh / 2).min(h),
                );
                let mut count = [[0usize; 2]; 2];
                for y in y0..y1 {
                    for x in x0..x1 {
                        let i = y * w + x;
                        let k = usize::from(obj[i]);
                        count[k][0] += 1;
                        count[k][1] += usize::from(obj[i] == (self.dfg[i] < self.dbg[i]));
                    }
                }
                let share = |c: [usize; 2]| {
                    if c[0] == 0 {
                        1.0
                    } else {
                        c[1] as f32 / c[0] as f32
                    }
                };
                0.5 * (share(count[0]) + share(count[1]))
            }
            _ => 0.0,
        };
        if self.fg.is_some() && agree < 0.85 && area > 0 {
            warnings.push(format!(
                "object and background colours overlap ({:.0}% agreement); check the mask",
                agree * 100.0
            ));
        }
        let confidence = if warnings.is_empty() {
            agree
        } else {
            agree.min(0.4)
        };
        self.labels.clone_from(&obj);
        self.result = build_segmentation(&obj, w, h, confidence, warnings)?;
        Ok(())
    }
}

/// The 0/1 mask (as [`Segmentation::object`] and, with no don't-care pixels, as
/// [`Segmentation::mask`]) and the bounding box of a binary object mask.
///
/// The fit takes the cut as it is, with no don't-care band along the outline: such a band
/// (±2 working pixels) hides where the edge is, and on the independent building benchmark it
/// cost accuracy (`cargo bench --bench building_bench -- --seed N`, mean IoU-64 over seeds
/// 0–2: plain ground 0.916 with it, 0.944 without; textured 0.863, 0.884; gradient 0.892,
/// 0.889), while on the Mitsuba dish photos it made no difference beyond the seeds' spread
/// (`cargo bench --bench dish_photo_bench -- --fov known --seed N`, seeds 0–3: 0.889 with it,
/// 0.886 without; photo-view IoU 0.982, 0.988). The mask loss already weighs an error of a
/// pixel or two along the outline lightly.
pub(super) fn build_segmentation(
    obj: &[bool],
    w: usize,
    h: usize,
    confidence: f32,
    warnings: Vec<String>,
) -> Result<Segmentation, SegmentError> {
    let object = Mask::new(
        w as u32,
        h as u32,
        obj.iter().map(|&o| if o { 1.0 } else { 0.0 }).collect(),
    )?;
    let mask = object.clone();
    Ok(Segmentation {
        object,
        mask,
        bbox: bbox_of(obj, w),
        confidence,
        warnings,
    })
}

/// Automatic segmentation of the half-size photo, upsampled to full size; `None` when the
/// photo is already small or nothing was found at half size.
fn coarse_labels(photo: &Photo, opts: &Options) -> Result<Option<Vec<bool>>, SegmentError> {
    let (w, h) = (photo.width() as usize, photo.height() as usize);
    if w * h < COARSE_MIN_PIXELS {
        return Ok(None);
    }
    let (cw, ch) = (w / 2, h / 2);
    let (rgba, _) = area_resample(photo.rgba(), w as u32, h as u32, 4, cw as u32, ch as u32);
    let small = Photo::from_parts(cw as u32, ch as u32, rgba, photo.source_size());
    let coarse = Session::automatic(&small, opts)?;
    if coarse.result.bbox.is_none() {
        return Ok(None);
    }
    let up = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w / 2).min(cw - 1), (i / w / 2).min(ch - 1));
            coarse.labels[y * cw + x]
        })
        .collect();
    Ok(Some(up))
}

/// Builds GrabCut's grid graph in `g` and cuts it: `data(i)` is the pixel's preference for the
/// source (object) side, > 0 object, < 0 background (a difference of data terms, or ±[`HARD`]);
/// edges link each pixel to its eight neighbours with the `nlinks` weights. With `reuse`, a
/// graph already built by an earlier call for the same grid and weights only gets its
/// capacities restored (the n-links never change within a session).
pub(super) fn cut_grid(
    g: &mut Graph,
    w: usize,
    h: usize,
    nlinks: &[[f32; 4]],
    reuse: bool,
    data: impl Fn(usize) -> f32,
) {
    if !(reuse && g.nodes() == w * h && g.restore()) {
        build_grid(g, w, h, nlinks);
    }
    for i in 0..w * h {
        let d = data(i).clamp(-HARD, HARD);
        if d > 0.0 {
            g.add_tweights(i, d, 0.0);
        } else {
            g.add_tweights(i, 0.0, -d);
        }
    }
    g.maxflow();
}

fn build_grid(g: &mut Graph, w: usize, h: usize, nlinks: &[[f32; 4]]) {
    g.reset(w * h, 4 * w * h);
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let nl = nlinks[i];
            if x + 1 < w {
                g.add_edge(i, i + 1, nl[0], nl[0]);
            }
            if y + 1 < h {
                g.add_edge(i, i + w, nl[1], nl[1]);
                if x + 1 < w {
                    g.add_edge(i, i + w + 1, nl[2], nl[2]);
                }
                if x > 0 {
                    g.add_edge(i, i + w - 1, nl[3], nl[3]);
                }
            }
        }
    }
    g.save();
}

/// Bounding box of the `true` pixels (end exclusive), if any.
pub(super) fn bbox_of(obj: &[bool], w: usize) -> Option<BBox> {
    let mut b: Option<BBox> = None;
    for (i, _) in obj.iter().enumerate().filter(|(_, o)| **o) {
        let (x, y) = ((i % w) as u32, (i / w) as u32);
        let bb = b.get_or_insert(BBox {
            x0: x,
            y0: y,
            x1: x + 1,
            y1: y + 1,
        });
        bb.x0 = bb.x0.min(x);
        bb.y0 = bb.y0.min(y);
        bb.x1 = bb.x1.max(x + 1);
        bb.y1 = bb.y1.max(y + 1);
    }
    b
}

/// What to tell the user when the object seems to run off the frame (`crossed`, from the
/// photo's colours) on two or more sides, or on a side the mask stops short of: the automatic
/// mask took those borders for background.
fn frame_warning(crossed: &[bool; 4], obj: &[bool], w: usize, h: usize) -> Option<String> {
    const NAMES: [&str; 4] = ["top", "bottom", "left", "right"];
    // Within 1 % of the side counts as reaching it.
    let (mx, my) = ((w / 100).max(1), (h / 100).max(1));
    let reaches = |s: usize| match s {
        0 => (0..my).any(|y| (0..w).any(|x| obj[y * w + x])),
        1 => (h - my..h).any(|y| (0..w).any(|x| obj[y * w + x])),
        2 => (0..h).any(|y| (0..mx).any(|x| obj[y * w + x])),
        _ => (0..h).any(|y| (w - mx..w).any(|x| obj[y * w + x])),
    };
    // The mask runs along a side whose colours are the background's: it took background in.
    let touches = touching(obj, w, h);
    if let Some(s) = (0..4).find(|&s| touches[s] && !crossed[s]) {
        return Some(format!(
            "the mask runs along the photo's {} edge, where the photo looks like background: \
             it may include background; check the mask and remove what is not the object \
             with the background brush",
            NAMES[s]
        ));
    }
    let sides: Vec<usize> = (0..4).filter(|&s| crossed[s]).collect();
    let short: Vec<&str> = sides
        .iter()
        .filter(|&&s| !reaches(s))
        .map(|&s| NAMES[s])
        .collect();
    if sides.len() < 2 && short.is_empty() {
        return None;
    }
    let names: Vec<&str> = sides.iter().map(|&s| NAMES[s]).collect();
    Some(if short.is_empty() {
        format!(
            "the object seems to run off the photo's {} edges or fill the frame: \
             check the mask, or use a photo with background around the object",
            names.join(" and ")
        )
    } else {
        format!(
            "the object seems to run off the photo's {} edge{} but the mask stops short of it, \
             so the mask may be a fragment: draw a box around the object or paint it with the \
             object brush, or use a photo with background around the object",
            short.join(" and "),
            if short.len() > 1 { "s" } else { "" }
        )
    })
}

/// Number of image sides on which the object covers more than a quarter of the side.
pub(super) fn touching_sides(obj: &[bool], w: usize, h: usize) -> usize {
    touching(obj, w, h).iter().filter(|&&t| t).count()
}

/// The sides (top, bottom, left, right) on which the object covers more than a quarter.
fn touching(obj: &[bool], w: usize, h: usize) -> [bool; 4] {
    let top = (0..w).filter(|&x| obj[x]).count();
    let bottom = (0..w).filter(|&x| obj[(h - 1) * w + x]).count();
    let left = (0..h).filter(|&y| obj[y * w]).count();
    let right = (0..h).filter(|&y| obj[y * w + w - 1]).count();
    [(top, w), (bottom, w), (left, h), (right, h)].map(|(c, len)| 4 * c > len)
}

/// Calls `f` for every pixel within `radius` of the stroke's polyline.
pub(super) fn for_stroke_pixels(
    stroke: &Stroke,
    w: usize,
    h: usize,
    mut f: impl FnMut(usize),
) -> Result<(), SegmentError> {
    let r = stroke.radius;
    if !(r.is_finite() && r > 0.0 && r <= 4096.0) {
        return Err(SegmentError(format!(
            "stroke radius {r} must be in (0, 4096]"
        )));
    }
    if stroke.points.is_empty() {
        return Err(SegmentError::new("a stroke needs at least one point"));
    }
    if stroke
        .points
        .iter()
        .any(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return Err(SegmentError::new("stroke points must be finite"));
    }
    let segs: Vec<([f32; 2], [f32; 2])> = if stroke.points.len() == 1 {
        vec![(stroke.points[0], stroke.points[0])]
    } else {
        stroke.points.windows(2).map(|p| (p[0], p[1])).collect()
    };
    for (a, b) in segs {
        let x0 = (a[0].min(b[0]) - r).floor().max(0.0) as usize;
        let y0 = (a[1].min(b[1]) - r).floor().max(0.0) as usize;
        let x1 = ((a[0].max(b[0]) + r).ceil().max(0.0) as usize).min(w);
        let y1 = ((a[1].max(b[1]) + r).ceil().max(0.0) as usize).min(h);
        let d = [b[0] - a[0], b[1] - a[1]];
        let len2 = d[0] * d[0] + d[1] * d[1];
        for y in y0..y1 {
            for x in x0..x1 {
                let p = [x as f32 + 0.5 - a[0], y as f32 + 0.5 - a[1]];
                let t = if len2 > 0.0 {
                    ((p[0] * d[0] + p[1] * d[1]) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let q = [p[0] - t * d[0], p[1] - t * d[1]];
                if q[0] * q[0] + q[1] * q[1] <= r * r {
                    f(y * w + x);
                }
            }
        }
    }
    Ok(())
}

/// A predicate "this colour looks like the pixels marked `which`", or `None` without marks.
fn stroke_colour_filter(colors: &[Rgb], hard: &[u8], which: u8) -> Option<impl Fn(&Rgb) -> bool> {
    let samples: Vec<Rgb> = colors
        .iter()
        .zip(hard)
        .filter(|(_, h)| **h == which)
        .map(|(c, _)| *c)
        .step_by(1)
        .take(MAX_SAMPLES)
        .collect();
    if samples.len() < 8 {
        return None;
    }
    let g = Gmm::fit(&samples, 2)?;
    // Neighbouring stroke pixels share JPEG blocks and lighting, so the stroke's spread
    // understates the region's: widen the acceptance by a margin (Mahalanobis² + 2·margin).
    let tau = percentile(samples.iter().map(|c| g.nll(c)).collect(), 0.98) + STROKE_MARGIN;
    Some(move |c: &Rgb| g.nll(c) <= tau)
}

/// The `p`-quantile of `v` (0 ≤ p ≤ 1).
fn percentile(mut v: Vec<f32>, p: f32) -> f32 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_unstable_by(f32::total_cmp);
    let k = ((v.len() - 1) as f32 * p).round() as usize;
    v[k.min(v.len() - 1)]
}

/// GrabCut's contrast-sensitive n-link weights γ/dist · exp(−β‖zᵢ − zⱼ‖²) with
/// β = 1 / (2⟨‖zᵢ − zⱼ‖²⟩) (eq. 11 and the text after it).
pub(super) fn nlinks_of(colors: &[Rgb], w: usize, h: usize) -> Vec<[f32; 4]> {
    let d2 =
        |a: &Rgb, b: &Rgb| (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2);
    let mut sum = 0.0f64;
    let mut count = 0usize;
    let mut raw = vec![[f32::NAN; 4]; w * h];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let c = &colors[i];
            let mut put = |k: usize, j: usize| {
                let v = d2(c, &colors[j]);
                raw[i][k] = v;
                sum += f64::from(v);
                count += 1;
            };
            if x + 1 < w {
                put(0, i + 1);
            }
            if y + 1 < h {
                put(1, i + w);
                if x + 1 < w {
                    put(2, i + w + 1);
                }
                if x > 0 {
                    put(3, i + w - 1);
                }
            }
        }
    }
    let mean = (sum / count.max(1) as f64).max(1e-8);
    let beta = (1.0 / (2.0 * mean)) as f32;
    let diag = GAMMA / std::f32::consts::SQRT_2;
    raw.iter()
        .map(|r| {
            let e = |k: usize, g: f32| {
                if r[k].is_nan() {
                    0.0
                } else {
                    g * (-beta * r[k]).exp()
                }
            };
            [e(0, GAMMA), e(1, GAMMA), e(2, diag), e(3, diag)]
        })
        .collect()
}

/// The border background model, the "background-like" threshold and the touched sides.
fn border_model(colors: &[Rgb], w: usize, h: usize) -> Result<(Gmm, f32, [bool; 4]), SegmentError> {
    let b = (w.min(h) / 40).max(2);
    let side = |s: usize| -> Vec<usize> {
        let mut v = Vec::new();
        match s {
            0 => (0..b).for_each(|y| (0..w).for_each(|x| v.push(y * w + x))),
            1 => (h - b..h).for_each(|y| (0..w).for_each(|x| v.push(y * w + x))),
            2 => (0..h).for_each(|y| (0..b).for_each(|x| v.push(y * w + x))),
            _ => (0..h).for_each(|y| (w - b..w).for_each(|x| v.push(y * w + x))),
        }
        v
    };
    let sides: Vec<Vec<usize>> = (0..4).map(side).collect();
    let sample = |idx: &mut dyn Iterator<Item = usize>, cap: usize| -> Vec<Rgb> {
        let all: Vec<usize> = idx.collect();
        let stride = (all.len() / cap).max(1);
        all.iter().step_by(stride).map(|&i| colors[i]).collect()
    };
    let mut touched = [false; 4];
    let mut keep: Vec<Rgb> = Vec::new();
    for s in 0..4 {
        let others = sample(
            &mut (0..4)
                .filter(|&o| o != s)
                .flat_map(|o| sides[o].iter().copied()),
            6000,
        );
        let model = Gmm::fit(&others, 2)
            .ok_or_else(|| SegmentError::new("internal: empty border sample"))?;
        let tau = percentile(others.iter().map(|c| model.nll(c)).collect(), 0.99);
        let own = sample(&mut sides[s].iter().copied(), 6000);
        let outliers: Vec<bool> = own.iter().map(|c| model.nll(c) > tau).collect();
        let frac = outliers.iter().filter(|&&o| o).count() as f32 / own.len().max(1) as f32;
        touched[s] = frac > TOUCH_FRACTION;
        keep.extend(
            own.iter()
                .zip(&outliers)
                .filter(|(_, o)| !touched[s] || !**o)
                .map(|(c, _)| *c),
        );
    }
    let model =
        Gmm::fit(&keep, 3).ok_or_else(|| SegmentError::new("internal: empty border sample"))?;
    let tau = percentile(
        keep.iter().map(|c| model.nll(c)).collect(),
        BORDER_PERCENTILE,
    );
    Ok((model, tau, touched))
}
