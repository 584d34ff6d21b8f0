//! Binary STL: an 80-byte header, the triangle count, then per triangle its unit face normal,
//! three corners (f32, little-endian, metres) and a zero attribute word.

use crate::generators::Mesh;
use crate::glb::GlbError;
use glam::Vec3;

/// The binary STL of every triangle of `mesh` (all parts together, counter-clockwise from
/// outside as the generators make them).
pub fn write_stl(mesh: &Mesh, title: &str) -> Result<Vec<u8>, GlbError> {
    mesh.check().map_err(|e| GlbError::Export(e.to_string()))?;
    let count = u32::try_from(mesh.triangles.len())
        .map_err(|_| GlbError::Export("more than 2³² triangles for STL".into()))?;
    if count == 0 {
        return Err(GlbError::Export("the mesh has no triangles".into()));
    }
    let mut out = Vec::with_capacity(84 + 50 * mesh.triangles.len());
    // A binary header must not start with "solid", or readers take the file for ASCII STL.
    let mut header = format!("procfit {} binary STL: {title}, metres", crate::VERSION).into_bytes();
    header.resize(80, b' ');
    out.extend_from_slice(&header[..80]);
    out.extend_from_slice(&count.to_le_bytes());
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let normal = (b - a).cross(c - a).normalize_or(Vec3::ZERO);
        for v in [normal, a, b, c] {
            for x in v.to_array() {
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
        out.extend_from_slice(&0u16.to_le_bytes());
    }
    Ok(out)
}
