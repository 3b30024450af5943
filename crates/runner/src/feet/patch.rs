//! The lowest flat patch of a set of shapes placed in the world: the sole rectangle a foot stands on.

use nalgebra::{Point3, Vector3};

use super::mesh::Triangle;

/// Points closer than this to the lowest point belong to the patch \[m\].
pub const PATCH_HEIGHT_TOLERANCE: f64 = 0.002;
/// A triangle is part of a flat bottom when its outward normal is within this of straight down \[deg\].
pub const PATCH_NORMAL_TOLERANCE_DEG: f64 = 10.0;

/// Shapes in world coordinates.
#[derive(Debug, Clone, Default)]
pub struct Shapes {
    /// Triangles (boxes, cylinders and meshes), outward normals by the right-hand rule.
    pub triangles: Vec<Triangle>,
    /// Spheres: centre \[m\] and radius \[m\].
    pub spheres: Vec<(Point3<f64>, f64)>,
}

impl Shapes {
    /// Lowest z of every shape \[m\] (`None` when there is none).
    pub fn lowest(&self) -> Option<f64> {
        let tri = self.triangles.iter().flatten().map(|p| p.z);
        let sph = self.spheres.iter().map(|(c, r)| c.z - r);
        tri.chain(sph).min_by(f64::total_cmp)
    }

    /// Whether there is no shape.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty() && self.spheres.is_empty()
    }
}

/// A horizontal rectangle, world x/y aligned, at height `z`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Patch {
    /// Centre of the rectangle (x, y) and its height z \[m\].
    pub centre: Point3<f64>,
    /// Size along world x \[m\].
    pub length: f64,
    /// Size along world y \[m\].
    pub width: f64,
    /// Points (vertices of downward flat triangles, lowest points of spheres) that span it.
    pub points: usize,
}

impl Patch {
    /// Area \[m²\].
    pub fn area(&self) -> f64 {
        self.length * self.width
    }
}

/// The lowest flat patch of `shapes`: the points within [`PATCH_HEIGHT_TOLERANCE`] of the lowest one
/// that are vertices of downward-facing triangles (normal within [`PATCH_NORMAL_TOLERANCE_DEG`] of −z)
/// lying entirely at that height, or lowest points of spheres; their x/y bounding rectangle. `None` when
/// those points span no area (a single sphere, an edge, a rounded bottom).
pub fn lowest_patch(shapes: &Shapes) -> Option<Patch> {
    let z0 = shapes.lowest()?;
    let near = |z: f64| z - z0 <= PATCH_HEIGHT_TOLERANCE;
    let cos = PATCH_NORMAL_TOLERANCE_DEG.to_radians().cos();
    let mut points: Vec<Point3<f64>> = Vec::new();
    for t in &shapes.triangles {
        let n = (t[1] - t[0]).cross(&(t[2] - t[0]));
        let norm = n.norm();
        if norm > 0.0 && -n.z / norm >= cos && t.iter().all(|p| near(p.z)) {
            points.extend_from_slice(t);
        }
    }
    for (c, r) in &shapes.spheres {
        if near(c.z - r) {
            points.push(c - Vector3::z() * *r);
        }
    }
    let (lo, hi) = points.iter().fold(
        (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.inf(&p.coords), hi.sup(&p.coords)),
    );
    let (length, width) = (hi.x - lo.x, hi.y - lo.y);
    if points.len() < 3 || length <= 1e-4 || width <= 1e-4 {
        return None;
    }
    let z = points.iter().map(|p| p.z).sum::<f64>() / points.len() as f64;
    Some(Patch {
        centre: Point3::new(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), z),
        length,
        width,
        points: points.len(),
    })
}
