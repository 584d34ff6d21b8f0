//! Silhouette losses over masks with a "don't care" value: mask MSE (paper eq. 1) and IoU.
