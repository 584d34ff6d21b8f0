//! Perspective pinhole camera and object transform, shared by the renderer, the fit and the exporter.
