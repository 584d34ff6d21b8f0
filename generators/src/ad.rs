//! Reverse-mode automatic differentiation for the generators: a [`Scalar`] trait that the
//! generators are written against once, implemented by plain `f64` (meshes) and by a tape
//! variable [`Var`] (derivatives), so a mesh and its Jacobian always come from the same code
//! (paper §3.3 uses CppAD for the same purpose).
//!
//! Design, chosen for speed and for rayon: the tape is a flat `Vec` of nodes, each with at most
//! two parents and their local partial derivatives; a `Var` is a value plus a node index
//! (`Copy`, no reference counting). Operations push onto a **thread-local** tape, so many
//! generators can record at once on different threads; [`record`] hands the finished tape to
//! its caller, which owns it from then on (a [`TapeVjp`] is `Send + Sync`). Constants never
//! touch the tape: an operation on two constants folds to a constant.

use crate::{GenError, Vjp};
use glam::Vec3;
use std::cell::RefCell;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// The number type a differentiable generator is written over.
///
/// Arithmetic with `Self` and with plain `f64` on the right-hand side; comparisons go through
/// [`Scalar::val`] (branches have zero derivative, as the paper assumes for discrete choices).
pub trait Scalar:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
{
    /// A constant (zero derivative).
    fn cst(v: f64) -> Self;
    /// The plain value.
    fn val(self) -> f64;
    /// Square root.
    fn sqrt(self) -> Self;
    /// Sine.
    fn sin(self) -> Self;
    /// Cosine.
    fn cos(self) -> Self;

    /// The larger of two values (derivative of the chosen one).
    fn max(self, o: Self) -> Self {
        if self.val() >= o.val() { self } else { o }
    }
    /// The smaller of two values (derivative of the chosen one).
    fn min(self, o: Self) -> Self {
        if self.val() <= o.val() { self } else { o }
    }
    /// A smooth maximum `≥ max(self, o)`, within `eps / 2` of it, with a continuous derivative:
    /// `(a + b + sqrt((a − b)² + eps²)) / 2`.
    fn smooth_max(self, o: Self, eps: f64) -> Self {
        let d = self - o;
        (self + o + (d * d + eps * eps).sqrt()) * 0.5
    }
    /// A smooth minimum `≤ min(self, o)`, the mirror of [`Scalar::smooth_max`].
    fn smooth_min(self, o: Self, eps: f64) -> Self {
        let d = self - o;
        (self + o - (d * d + eps * eps).sqrt()) * 0.5
    }
    /// `max(self, 0)²`: a hinge penalty with a continuous derivative.
    fn relu_sq(self) -> Self {
        if self.val() > 0.0 {
            self * self
        } else {
            Self::cst(0.0)
        }
    }
}

impl Scalar for f64 {
    #[inline]
    fn cst(v: f64) -> Self {
        v
    }
    #[inline]
    fn val(self) -> f64 {
        self
    }
    #[inline]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline]
    fn sin(self) -> Self {
        f64::sin(self)
    }
    #[inline]
    fn cos(self) -> Self {
        f64::cos(self)
    }
}

/// Node index that marks a constant (no node on the tape).
const NONE: u32 = u32::MAX;

/// One tape entry: up to two parents and d(this)/d(parent).
#[derive(Clone, Copy, Debug)]
struct Node {
    a: u32,
    b: u32,
    da: f64,
    db: f64,
}

thread_local! {
    static TAPE: RefCell<Vec<Node>> = const { RefCell::new(Vec::new()) };
}

#[inline]
fn push(node: Node) -> u32 {
    TAPE.with(|t| {
        let mut t = t.borrow_mut();
        t.push(node);
        (t.len() - 1) as u32
    })
}

/// A differentiable scalar recorded on the current thread's tape.
#[derive(Clone, Copy, Debug)]
pub struct Var {
    v: f64,
    i: u32,
}

impl Var {
    /// A new independent variable (a leaf on the tape). Only meaningful inside [`record`].
    pub fn input(v: f64) -> Var {
        let i = push(Node {
            a: NONE,
            b: NONE,
            da: 0.0,
            db: 0.0,
        });
        Var { v, i }
    }

    /// The tape node of this variable, or `None` for a constant.
    pub fn node(self) -> Option<u32> {
        (self.i != NONE).then_some(self.i)
    }

    #[inline]
    fn unary(v: f64, x: Var, dx: f64) -> Var {
        if x.i == NONE {
            return Var { v, i: NONE };
        }
        let i = push(Node {
            a: x.i,
            b: NONE,
            da: dx,
            db: 0.0,
        });
        Var { v, i }
    }

    #[inline]
    fn binary(v: f64, x: Var, dx: f64, y: Var, dy: f64) -> Var {
        match (x.i == NONE, y.i == NONE) {
            (true, true) => Var { v, i: NONE },
            (false, true) => Var::unary(v, x, dx),
            (true, false) => Var::unary(v, y, dy),
            (false, false) => {
                let i = push(Node {
                    a: x.i,
                    b: y.i,
                    da: dx,
                    db: dy,
                });
                Var { v, i }
            }
        }
    }
}

impl Add for Var {
    type Output = Var;
    #[inline]
    fn add(self, o: Var) -> Var {
        Var::binary(self.v + o.v, self, 1.0, o, 1.0)
    }
}
impl Sub for Var {
    type Output = Var;
    #[inline]
    fn sub(self, o: Var) -> Var {
        Var::binary(self.v - o.v, self, 1.0, o, -1.0)
    }
}
impl Mul for Var {
    type Output = Var;
    #[inline]
    fn mul(self, o: Var) -> Var {
        Var::binary(self.v * o.v, self, o.v, o, self.v)
    }
}
impl Div for Var {
    type Output = Var;
    #[inline]
    fn div(self, o: Var) -> Var {
        let q = self.v / o.v;
        Var::binary(q, self, 1.0 / o.v, o, -q / o.v)
    }
}
impl Neg for Var {
    type Output = Var;
    #[inline]
    fn neg(self) -> Var {
        Var::unary(-self.v, self, -1.0)
    }
}
impl Add<f64> for Var {
    type Output = Var;
    #[inline]
    fn add(self, o: f64) -> Var {
        Var::unary(self.v + o, self, 1.0)
    }
}
impl Sub<f64> for Var {
    type Output = Var;
    #[inline]
    fn sub(self, o: f64) -> Var {
        Var::unary(self.v - o, self, 1.0)
    }
}
impl Mul<f64> for Var {
    type Output = Var;
    #[inline]
    fn mul(self, o: f64) -> Var {
        Var::unary(self.v * o, self, o)
    }
}
impl Div<f64> for Var {
    type Output = Var;
    #[inline]
    fn div(self, o: f64) -> Var {
        Var::unary(self.v / o, self, 1.0 / o)
    }
}

impl Scalar for Var {
    #[inline]
    fn cst(v: f64) -> Self {
        Var { v, i: NONE }
    }
    #[inline]
    fn val(self) -> f64 {
        self.v
    }
    #[inline]
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        // d sqrt(x) = 1 / (2 sqrt(x)); at 0 the derivative is infinite, callers keep x > 0.
        Var::unary(s, self, 0.5 / s)
    }
    #[inline]
    fn sin(self) -> Self {
        Var::unary(self.v.sin(), self, self.v.cos())
    }
    #[inline]
    fn cos(self) -> Self {
        Var::unary(self.v.cos(), self, -self.v.sin())
    }
}

/// A finished recording: the nodes in creation order.
#[derive(Clone, Debug, Default)]
pub struct Tape {
    nodes: Vec<Node>,
}

impl Tape {
    /// Number of nodes recorded.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Propagates `adj` (one adjoint per node, seeded at the outputs) back to the leaves, in
    /// place: afterwards `adj[leaf]` is dL/d(leaf).
    pub fn reverse(&self, adj: &mut [f64]) {
        for (n, node) in self.nodes.iter().enumerate().rev() {
            let g = adj[n];
            if g == 0.0 {
                continue;
            }
            if node.a != NONE {
                adj[node.a as usize] += g * node.da;
            }
            if node.b != NONE {
                adj[node.b as usize] += g * node.db;
            }
        }
    }
}

/// Runs `f` with a fresh tape on this thread and returns its result with the recorded tape.
/// Re-entrant: a recording inside a recording gets its own tape and restores the outer one,
/// also when `f` unwinds.
pub fn record<R>(f: impl FnOnce() -> R) -> (R, Tape) {
    /// Puts the outer tape back when dropped, so a panic inside `f` cannot leave this thread
    /// recording onto a stale tape.
    struct Restore(Option<Vec<Node>>);
    impl Drop for Restore {
        fn drop(&mut self) {
            if let Some(outer) = self.0.take() {
                TAPE.with(|t| *t.borrow_mut() = outer);
            }
        }
    }
    let mut guard = Restore(Some(TAPE.with(|t| std::mem::take(&mut *t.borrow_mut()))));
    let r = f();
    let outer = guard.0.take().unwrap_or_default();
    let nodes = TAPE.with(|t| std::mem::replace(&mut *t.borrow_mut(), outer));
    (r, Tape { nodes })
}

/// Value and gradient of a scalar function of `x`, recorded once and swept back once; entries
/// of `x` flagged `false` in `active` are held constant and get a zero derivative.
pub fn gradient(x: &[f64], active: &[bool], f: impl FnOnce(&[Var]) -> Var) -> (f64, Vec<f64>) {
    let ((y, leaves), tape) = record(|| {
        let vars: Vec<Var> = x
            .iter()
            .zip(active.iter().chain(std::iter::repeat(&false)))
            .map(|(&v, &a)| if a { Var::input(v) } else { Var::cst(v) })
            .collect();
        let y = f(&vars);
        (y, vars)
    });
    let mut g = vec![0.0; x.len()];
    if let Some(out) = y.node() {
        let mut adj = vec![0.0; tape.len()];
        adj[out as usize] = 1.0;
        tape.reverse(&mut adj);
        for (gi, l) in g.iter_mut().zip(&leaves) {
            if let Some(n) = l.node() {
                *gi = adj[n as usize];
            }
        }
    }
    (y.val(), g)
}

/// The vector–Jacobian product of a generated mesh (paper eq. 2): the tape of the generation,
/// the tape node of every vertex coordinate and the node of every continuous parameter.
#[derive(Clone, Debug)]
pub struct TapeVjp {
    tape: Tape,
    /// Node per vertex coordinate (`NONE` for coordinates that do not depend on parameters).
    outputs: Vec<[u32; 3]>,
    /// Node per parameter (`NONE` for discrete ones).
    inputs: Vec<u32>,
}

impl TapeVjp {
    /// Wraps a recording whose leaves are `inputs` (one per parameter) and whose outputs are
    /// the mesh positions `outputs`.
    pub fn new(tape: Tape, inputs: &[Var], outputs: &[[Var; 3]]) -> TapeVjp {
        TapeVjp {
            tape,
            outputs: outputs.iter().map(|p| p.map(|c| c.i)).collect(),
            inputs: inputs.iter().map(|v| v.i).collect(),
        }
    }

    /// Number of tape nodes (a measure of the gradient's cost).
    pub fn tape_len(&self) -> usize {
        self.tape.len()
    }
}

impl Vjp for TapeVjp {
    fn vjp(&self, d_positions: &[Vec3], d_params: &mut [f64]) -> Result<(), GenError> {
        if d_positions.len() != self.outputs.len() {
            return Err(GenError::AdjointLength {
                expected: self.outputs.len(),
                got: d_positions.len(),
            });
        }
        if d_params.len() != self.inputs.len() {
            return Err(GenError::WrongLength {
                expected: self.inputs.len(),
                got: d_params.len(),
            });
        }
        let mut adj = vec![0.0; self.tape.len()];
        for (o, d) in self.outputs.iter().zip(d_positions) {
            for k in 0..3 {
                if o[k] != NONE {
                    adj[o[k] as usize] += f64::from(d[k]);
                }
            }
        }
        self.tape.reverse(&mut adj);
        for (dp, &n) in d_params.iter_mut().zip(&self.inputs) {
            if n != NONE {
                *dp += adj[n as usize];
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f<S: Scalar>(x: &[S]) -> S {
        // Exercises every operation once.
        let a = x[0] * x[1] + x[0].sin() - x[1].cos() / x[0];
        let b = (a * a + 1.0).sqrt() * 2.0 - x[1] / 3.0 + (-x[0]) - 0.5;
        b.smooth_max(x[1], 0.1) + (x[0] - x[1]).relu_sq()
    }

    #[test]
    fn gradient_matches_central_differences() {
        let x = [0.7, 1.3];
        let (v, g) = gradient(&x, &[true, true], f);
        assert!((v - f(&x)).abs() < 1e-12);
        for k in 0..2 {
            let h = 1e-6;
            let mut p = x;
            let mut m = x;
            p[k] += h;
            m[k] -= h;
            let fd = (f(&p) - f(&m)) / (2.0 * h);
            assert!(
                (fd - g[k]).abs() < 1e-6 * (1.0 + fd.abs()),
                "{k}: {fd} vs {}",
                g[k]
            );
        }
    }

    #[test]
    fn nested_and_unwinding_recordings_restore_the_outer_tape() {
        let ((inner_len, outer_var), outer) = record(|| {
            let a = Var::input(1.0);
            let b = a * a;
            let (_, inner) = record(|| Var::input(2.0) * 3.0);
            let caught = std::panic::catch_unwind(|| {
                record(|| {
                    let _ = Var::input(5.0) * 2.0;
                    panic!("generator bug");
                })
            });
            assert!(caught.is_err());
            (inner.len(), b + a)
        });
        assert_eq!(inner_len, 2);
        // Outer: a, b = a·a, b + a — nothing of the inner or the unwound recording.
        assert_eq!(outer.len(), 3);
        assert_eq!(outer_var.node(), Some(2));
    }

    #[test]
    fn constants_do_not_touch_the_tape() {
        let (_, tape) = record(|| {
            let c = Var::cst(2.0);
            (c * c + 1.0).sqrt().val()
        });
        assert!(tape.is_empty());
        let (_, g) = gradient(&[1.0, 2.0], &[true, false], |x| x[0] * x[1]);
        assert_eq!(g, vec![2.0, 0.0]);
    }
}
