//! Silhouette rasterizer: anti-aliased coverage from tiny-skia and exact edge-sampling gradients.
