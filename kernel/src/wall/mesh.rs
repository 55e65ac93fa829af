//! Triangle meshes (STL, read with the `stl_io` crate), two-sided.
//!
//! A sphere may touch several triangles at once. Contacts through a shared edge or vertex
//! would be counted twice (and a flat seam would push sideways), so the simulation keeps a
//! triangle's contact only if its closest point does not lie on a triangle already accepted
//! nearer to the centre (see `Shape::feature_distance`).

use super::{Hit, Shape};
use glam::DVec3;
use std::path::Path;

#[derive(Debug, Clone)]
pub struct Mesh {
    pub triangles: Vec<[DVec3; 3]>,
    /// Uniform grid over the mesh bounds; each cell lists the triangles whose boxes touch it.
    grid_origin: DVec3,
    grid_cell: f64,
    grid_dims: [usize; 3],
    grid_start: Vec<u32>,
    grid_items: Vec<u32>,
    reference: DVec3,
}

/// Why a mesh could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    #[error("cannot read STL file {path}: {reason}")]
    Read {
        path: String,
        reason: std::io::Error,
    },
    #[error("STL file {path} has no triangles")]
    Empty { path: String },
    #[error("STL file {path}: triangle {index} has a non-finite or repeated vertex")]
    Degenerate { path: String, index: usize },
}

impl Mesh {
    /// Loads an ASCII or binary STL file, scaling coordinates by `scale` (e.g. 1e-3 for mm).
    pub fn from_stl(path: &Path, scale: f64) -> Result<Mesh, MeshError> {
        let p = path.display().to_string();
        let mut file = std::fs::File::open(path).map_err(|reason| MeshError::Read {
            path: p.clone(),
            reason,
        })?;
        let stl = stl_io::read_stl(&mut file).map_err(|reason| MeshError::Read {
            path: p.clone(),
            reason,
        })?;
        let v = |i: usize| {
            let a = stl.vertices[i];
            DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64) * scale
        };
        let tris: Vec<[DVec3; 3]> = stl
            .faces
            .iter()
            .map(|f| [v(f.vertices[0]), v(f.vertices[1]), v(f.vertices[2])])
            .collect();
        if tris.is_empty() {
            return Err(MeshError::Empty { path: p });
        }
        for (index, t) in tris.iter().enumerate() {
            let area2 = (t[1] - t[0]).cross(t[2] - t[0]).length();
            if !t.iter().all(|x| x.is_finite()) || area2 == 0.0 {
                return Err(MeshError::Degenerate { path: p, index });
            }
        }
        Ok(Mesh::new(tris))
    }

    pub fn new(triangles: Vec<[DVec3; 3]>) -> Mesh {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        let mut mean_size = 0.0;
        for t in &triangles {
            for p in t {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
            let (a, b) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
            mean_size += (b - a).max_element();
        }
        mean_size /= triangles.len().max(1) as f64;
        let extent = hi - lo;
        let mut cell = mean_size.max(extent.max_element() / 256.0).max(1e-9);
        let cells = |c: f64| ((extent / c).floor() + DVec3::ONE).as_uvec3();
        while {
            let d = cells(cell);
            (d.x as u64) * (d.y as u64) * (d.z as u64) > 4_000_000
        } {
            cell *= 1.5;
        }
        let d = cells(cell);
        let dims = [d.x as usize, d.y as usize, d.z as usize];
        let mut mesh = Mesh {
            reference: (lo + hi) * 0.5,
            triangles,
            grid_origin: lo,
            grid_cell: cell,
            grid_dims: dims,
            grid_start: vec![],
            grid_items: vec![],
        };
        let mut lists: Vec<Vec<u32>> = vec![vec![]; dims[0] * dims[1] * dims[2]];
        for (k, t) in mesh.triangles.iter().enumerate() {
            let (a, b) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
            mesh.for_cells(a, b, |c| lists[c].push(k as u32));
        }
        mesh.grid_start.push(0);
        for l in &lists {
            mesh.grid_items.extend_from_slice(l);
            mesh.grid_start.push(mesh.grid_items.len() as u32);
        }
        mesh
    }

    fn for_cells(&self, a: DVec3, b: DVec3, mut f: impl FnMut(usize)) {
        let idx = |p: DVec3, k: usize| {
            let q = (p[k] - self.grid_origin[k]) / self.grid_cell;
            (q.max(0.0) as usize).min(self.grid_dims[k] - 1)
        };
        if b.x < self.grid_origin.x - self.grid_cell
            || b.y < self.grid_origin.y - self.grid_cell
            || b.z < self.grid_origin.z - self.grid_cell
        {
            return;
        }
        for z in idx(a, 2)..=idx(b, 2) {
            for y in idx(a, 1)..=idx(b, 1) {
                for x in idx(a, 0)..=idx(b, 0) {
                    f((z * self.grid_dims[1] + y) * self.grid_dims[0] + x);
                }
            }
        }
    }
}

/// Closest point to `p` on triangle (a, b, c) by Voronoi regions (Ericson, Real-Time
/// Collision Detection, 5.1.5).
pub fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

impl Shape for Mesh {
    fn hits(&self, x: DVec3, range: f64, out: &mut Vec<Hit>) {
        let mut cand: Vec<u32> = vec![];
        self.for_cells(x - DVec3::splat(range), x + DVec3::splat(range), |c| {
            cand.extend_from_slice(
                &self.grid_items[self.grid_start[c] as usize..self.grid_start[c + 1] as usize],
            );
        });
        cand.sort_unstable();
        cand.dedup();
        for k in cand {
            let h = self.hit(k, x);
            if h.distance < range {
                out.push(h);
            }
        }
    }

    fn hit(&self, feature: u32, x: DVec3) -> Hit {
        let [a, b, c] = self.triangles[feature as usize];
        let point = closest_on_triangle(x, a, b, c);
        let d = x - point;
        let dist = d.length();
        let normal = if dist > 0.0 {
            d / dist
        } else {
            (b - a).cross(c - a).normalize()
        };
        Hit {
            feature,
            point,
            normal,
            distance: dist,
        }
    }

    fn reference_point(&self) -> DVec3 {
        self.reference
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_point_regions() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        let p = closest_on_triangle(DVec3::new(0.2, 0.2, 1.0), a, b, c);
        assert!((p - DVec3::new(0.2, 0.2, 0.0)).length() < 1e-15, "{p:?}");
        assert_eq!(closest_on_triangle(DVec3::new(-1.0, -1.0, 0.5), a, b, c), a);
        assert_eq!(
            closest_on_triangle(DVec3::new(0.5, -1.0, 0.0), a, b, c),
            DVec3::new(0.5, 0.0, 0.0)
        );
        let p = closest_on_triangle(DVec3::new(1.0, 1.0, 0.0), a, b, c);
        assert!((p - DVec3::new(0.5, 0.5, 0.0)).length() < 1e-15);
    }
}
