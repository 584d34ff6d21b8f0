//! Silhouette losses over masks with a "don't care" value: mask MSE (paper eq. 1) and IoU.
//!
//! Pixels whose target is [`Mask::DONT_CARE`] are left out of both the value and the adjoint
//! (they are the user's "unknown" marks or an uncertainty band around a segmented edge). The
//! MSE is the mean over the pixels that count; eq. 1 then averages it over views, which
//! [`mse_with_adjoint`] supports through its `weight` (1/N per view).

use crate::mask::Mask;
use std::fmt;

/// A loss that cannot be computed (mismatched sizes).
#[derive(Clone, Debug, PartialEq)]
pub struct LossError(pub String);

impl fmt::Display for LossError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for LossError {}

fn check_len(coverage: &[f32], target: &Mask) -> Result<(), LossError> {
    let n = target.width() as usize * target.height() as usize;
    if coverage.len() != n {
        return Err(LossError(format!(
            "image has {} pixels, mask is {}×{}",
            coverage.len(),
            target.width(),
            target.height()
        )));
    }
    Ok(())
}

/// Mean squared error between `coverage` and `target` over the pixels that count (0 when none
/// count).
pub fn mse(coverage: &[f32], target: &Mask) -> Result<f64, LossError> {
    check_len(coverage, target)?;
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (&c, &m) in coverage.iter().zip(target.values()) {
        if m != Mask::DONT_CARE {
            let d = f64::from(c) - f64::from(m);
            sum += d * d;
            n += 1;
        }
    }
    Ok(if n == 0 { 0.0 } else { sum / n as f64 })
}

/// `weight ×` [`mse`], and its adjoint `dL/dI = weight · 2(I − M)/n` written into `adjoint`
/// (0 on don't-care pixels). With `weight = 1/N` for each of N views, the sum over views is
/// eq. 1's multi-view mean.
pub fn mse_with_adjoint(
    coverage: &[f32],
    target: &Mask,
    weight: f64,
    adjoint: &mut [f32],
) -> Result<f64, LossError> {
    check_len(coverage, target)?;
    if adjoint.len() != coverage.len() {
        return Err(LossError(format!(
            "adjoint buffer has {} values for {} pixels",
            adjoint.len(),
            coverage.len()
        )));
    }
    if !weight.is_finite() {
        return Err(LossError(format!("loss weight {weight} is not finite")));
    }
    let n = target
        .values()
        .iter()
        .filter(|&&m| m != Mask::DONT_CARE)
        .count();
    if n == 0 {
        adjoint.fill(0.0);
        return Ok(0.0);
    }
    let scale = weight / n as f64;
    let mut sum = 0.0f64;
    for ((&c, &m), a) in coverage.iter().zip(target.values()).zip(adjoint.iter_mut()) {
        if m == Mask::DONT_CARE {
            *a = 0.0;
        } else {
            let d = f64::from(c) - f64::from(m);
            sum += d * d;
            *a = (2.0 * d * scale) as f32;
        }
    }
    Ok(sum * scale)
}

/// Intersection over union `Σ min(I, M) / Σ max(I, M)` over the pixels that count (the usual
/// IoU for binary images). Two empty silhouettes have IoU 1.
pub fn iou(coverage: &[f32], target: &Mask) -> Result<f64, LossError> {
    check_len(coverage, target)?;
    let (mut inter, mut union) = (0.0f64, 0.0f64);
    for (&c, &m) in coverage.iter().zip(target.values()) {
        if m != Mask::DONT_CARE {
            let c = f64::from(c.clamp(0.0, 1.0));
            inter += c.min(f64::from(m));
            union += c.max(f64::from(m));
        }
    }
    Ok(if union == 0.0 { 1.0 } else { inter / union })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mse_and_iou_skip_dont_care() {
        let m = Mask::new(2, 2, vec![1.0, 0.0, Mask::DONT_CARE, 1.0]).unwrap();
        let img = [0.5, 0.0, 1.0, 1.0];
        assert!((mse(&img, &m).unwrap() - 0.25 / 3.0).abs() < 1e-12);
        assert!((iou(&img, &m).unwrap() - 1.5 / 2.0).abs() < 1e-12);
        let mut adj = [9.0f32; 4];
        let l = mse_with_adjoint(&img, &m, 0.5, &mut adj).unwrap();
        assert!((l - 0.125 / 3.0).abs() < 1e-12);
        assert_eq!(adj, [(2.0 * -0.5 * 0.5 / 3.0) as f32, 0.0, 0.0, 0.0]);
        assert!(mse(&img[..3], &m).is_err());
        assert!(mse_with_adjoint(&img, &m, 1.0, &mut adj[..2]).is_err());
    }

    #[test]
    fn adjoint_is_the_gradient_of_mse() {
        let m = Mask::new(3, 1, vec![0.2, 1.0, 0.0]).unwrap();
        let img = [0.7f32, 0.4, 0.1];
        let mut adj = [0.0f32; 3];
        mse_with_adjoint(&img, &m, 1.0, &mut adj).unwrap();
        for i in 0..3 {
            let (mut a, mut b) = (img, img);
            a[i] += 1e-3;
            b[i] -= 1e-3;
            let fd = (mse(&a, &m).unwrap() - mse(&b, &m).unwrap()) / 2e-3;
            assert!((fd - f64::from(adj[i])).abs() < 1e-4, "pixel {i}");
        }
    }
}
