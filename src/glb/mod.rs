//! glTF 2.0 binary (GLB) export and import of procfit models and reference meshes.
