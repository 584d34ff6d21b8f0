//! Small welded, indexed meshes with known shapes (cube, UV sphere, lathes, open tube) for the
//! renderer's tests and benchmarks, and for later rooms that need a known shape without a
//! generator. Triangles are counter-clockwise seen from outside, like every procfit mesh.

use crate::generators::{Mesh, Part};
use glam::{Vec2, Vec3};

/// Wraps positions and triangles into a [`Mesh`]: flat per-corner normals, zero UVs, one part
/// (`part_name`) for every triangle.
pub fn mesh_from(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>, part_name: &'static str) -> Mesh {
    let mut corner_normals = Vec::with_capacity(3 * triangles.len());
    for t in &triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a).normalize_or(Vec3::Y);
        corner_normals.extend([n; 3]);
    }
    Mesh {
        corner_uvs: vec![Vec2::ZERO; 3 * triangles.len()],
        tri_parts: vec![0; triangles.len()],
        parts: vec![Part {
            name: part_name,
            color: [0.8, 0.8, 0.8, 1.0],
        }],
        positions,
        triangles,
        corner_normals,
    }
}

/// An axis-aligned cube of half-size `half` centred at the origin: 8 vertices, 12 triangles.
pub fn cube(half: f32) -> Mesh {
    let positions: Vec<Vec3> = (0..8)
        .map(|i| {
            let s = |bit: u32| if i & (1 << bit) != 0 { half } else { -half };
            Vec3::new(s(0), s(1), s(2))
        })
        .collect();
    let index = |p: Vec3| -> u32 {
        u32::from(p.x > 0.0) | (u32::from(p.y > 0.0) << 1) | (u32::from(p.z > 0.0) << 2)
    };
    let mut triangles = Vec::with_capacity(12);
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            let mut u = Vec3::ZERO;
            u[(axis + 1) % 3] = 1.0;
            let v = n.cross(u); // u × v = n for a right-handed (u, v, n)
            let c = [n - u - v, n + u - v, n + u + v, n - u + v].map(index);
            triangles.push([c[0], c[1], c[2]]);
            triangles.push([c[0], c[2], c[3]]);
        }
    }
    mesh_from(positions, triangles, "cube")
}

/// A surface of revolution about +Y. `profile` holds `[radius, y]` points; walking it
/// counter-clockwise in the (radius right, y up) half-plane puts the outside on the right, which
/// gives outward-facing triangles. Points with radius 0 become a single pole vertex. `sectors`
/// (≥ 3) is the number of divisions around the axis.
pub fn lathe(profile: &[[f32; 2]], sectors: u32, part_name: &'static str) -> Mesh {
    let sectors = sectors.max(3);
    let mut positions = Vec::new();
    let mut ring_index = Vec::with_capacity(profile.len());
    for &[r, y] in profile {
        ring_index.push(positions.len() as u32);
        if r == 0.0 {
            positions.push(Vec3::new(0.0, y, 0.0));
        } else {
            for j in 0..sectors {
                let phi = std::f32::consts::TAU * j as f32 / sectors as f32;
                positions.push(Vec3::new(r * phi.sin(), y, r * phi.cos()));
            }
        }
    }
    let idx = |i: usize, j: u32| -> u32 {
        if profile[i][0] == 0.0 {
            ring_index[i]
        } else {
            ring_index[i] + j % sectors
        }
    };
    let mut triangles = Vec::new();
    for i in 0..profile.len().saturating_sub(1) {
        for j in 0..sectors {
            let (a, b, c, d) = (idx(i, j), idx(i, j + 1), idx(i + 1, j + 1), idx(i + 1, j));
            for t in [[a, b, c], [a, c, d]] {
                if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                    triangles.push(t);
                }
            }
        }
    }
    mesh_from(positions, triangles, part_name)
}

/// A UV sphere of `radius` about the origin: `rings` latitude bands (≥ 2), `sectors` longitudes.
pub fn uv_sphere(radius: f32, rings: u32, sectors: u32) -> Mesh {
    let rings = rings.max(2);
    let profile: Vec<[f32; 2]> = (0..=rings)
        .map(|i| {
            let th = -std::f32::consts::FRAC_PI_2 + std::f32::consts::PI * i as f32 / rings as f32;
            let r = if i == 0 || i == rings {
                0.0
            } else {
                radius * th.cos()
            };
            [r, radius * th.sin()]
        })
        .collect();
    lathe(&profile, sectors, "sphere")
}

/// A closed, thick-walled cup about +Y (outer radius 0.5, height 1, wall 0.06, base on
/// y = −0.5): a concave lathe that hides parts of itself. About `rings_per_wall` × 2 + 7 profile
/// points; vertex count ≈ profile points × `sectors`.
pub fn cup(rings_per_wall: u32, sectors: u32) -> Mesh {
    let n = rings_per_wall.max(1);
    let (ro, wall, y0, y1) = (0.5f32, 0.06f32, -0.5f32, 0.5f32);
    let mut profile = vec![[0.0, y0], [0.8 * ro, y0], [ro * 0.95, y0 + 0.02]];
    // Outer wall, flaring slightly towards the rim.
    for i in 0..=n {
        let s = i as f32 / n as f32;
        profile.push([ro * (0.95 + 0.05 * s), y0 + 0.05 + (y1 - y0 - 0.05) * s]);
    }
    profile.push([ro - 0.5 * wall, y1 + 0.01]);
    // Inner wall back down.
    for i in 0..=n {
        let s = 1.0 - i as f32 / n as f32;
        profile.push([
            ro * (0.95 + 0.05 * s) - wall,
            y0 + wall + 0.05 + (y1 - y0 - wall - 0.05) * s,
        ]);
    }
    profile.push([0.7 * ro, y0 + wall]);
    profile.push([0.0, y0 + wall]);
    lathe(&profile, sectors, "cup")
}

/// An open tube (no caps): radius `radius`, from y = −h/2 to h/2. Seen from an angle its inside
/// shows, so its silhouette comes from boundary edges and back faces.
pub fn open_tube(radius: f32, height: f32, sectors: u32) -> Mesh {
    lathe(
        &[[radius, -0.5 * height], [radius, 0.5 * height]],
        sectors,
        "tube",
    )
}

/// `mesh` moved by `offset` and scaled by `scale` about the origin (scale first).
pub fn transformed(mesh: &Mesh, scale: f32, offset: Vec3) -> Mesh {
    let mut m = mesh.clone();
    for p in &mut m.positions {
        *p = *p * scale + offset;
    }
    m
}

/// Both meshes in one, `b`'s triangles after `a`'s, parts concatenated.
pub fn merged(a: &Mesh, b: &Mesh) -> Mesh {
    let mut m = a.clone();
    let (nv, np) = (a.positions.len() as u32, a.parts.len() as u8);
    m.positions.extend_from_slice(&b.positions);
    m.triangles
        .extend(b.triangles.iter().map(|t| t.map(|i| i + nv)));
    m.corner_normals.extend_from_slice(&b.corner_normals);
    m.corner_uvs.extend_from_slice(&b.corner_uvs);
    m.tri_parts.extend(b.tri_parts.iter().map(|&p| p + np));
    m.parts.extend_from_slice(&b.parts);
    m
}

/// Signed volume enclosed by a closed mesh (positive when its triangles face outwards).
pub fn signed_volume(mesh: &Mesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_closed(mesh: &Mesh, volume: f64, tol: f64) {
        mesh.check().unwrap();
        let v = signed_volume(mesh);
        assert!((v - volume).abs() < tol, "volume {v}, expected {volume}");
        // Closed and consistently oriented: every directed edge appears once, its reverse once.
        let mut dir = std::collections::HashMap::new();
        for t in &mesh.triangles {
            for k in 0..3 {
                *dir.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &dir {
            assert_eq!(n, 1, "edge {a}→{b} used {n} times");
            assert_eq!(dir.get(&(b, a)), Some(&1), "edge {a}→{b} has no twin");
        }
    }

    #[test]
    fn known_shapes_are_closed_and_outward() {
        check_closed(&cube(0.5), 1.0, 1e-6);
        let pi = std::f64::consts::PI;
        check_closed(&uv_sphere(1.0, 32, 64), 4.0 / 3.0 * pi, 0.03);
        check_closed(&cup(8, 32), 0.2, 0.03);
        assert_eq!(uv_sphere(1.0, 4, 8).positions.len(), 3 * 8 + 2);
    }
}
