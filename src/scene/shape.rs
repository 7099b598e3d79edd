//! The primitive kinds the SPD scenes contain, and their exact bounding boxes.

use super::math::{add, cross, length, normalize, scale, sub, V3};

#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    Sphere {
        center: V3,
        radius: f64,
    },
    /// Open cylinder or cone (no caps) from `base` to `apex`.
    Cone {
        base: V3,
        base_radius: f64,
        apex: V3,
        apex_radius: f64,
    },
    /// Planar polygon, convex or concave; its first three vertices span a
    /// convex corner (the SPD guarantees it), which gives the plane.
    Polygon {
        vertices: Vec<V3>,
    },
    /// Triangle with per-vertex normals (smooth shaded, double sided).
    Patch {
        vertices: [V3; 3],
        normals: [V3; 3],
    },
}

/// An open cone's frame: unit axis from base to apex, height, and radius
/// slope (apex radius - base radius) / height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConeFrame {
    pub axis: V3,
    pub height: f64,
    pub slope: f64,
}

impl ConeFrame {
    pub fn new(base: V3, base_radius: f64, apex: V3, apex_radius: f64) -> ConeFrame {
        let d = sub(apex, base);
        let height = length(d);
        ConeFrame {
            axis: scale(d, 1.0 / height),
            height,
            slope: (apex_radius - base_radius) / height,
        }
    }
}

/// Axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub lo: V3,
    pub hi: V3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        lo: [f64::INFINITY; 3],
        hi: [f64::NEG_INFINITY; 3],
    };

    pub fn grow(&mut self, p: V3) {
        for ((lo, hi), v) in self.lo.iter_mut().zip(self.hi.iter_mut()).zip(p) {
            *lo = lo.min(v);
            *hi = hi.max(v);
        }
    }

    pub fn union(&mut self, b: &Aabb) {
        self.grow(b.lo);
        self.grow(b.hi);
    }

    pub fn size(&self) -> V3 {
        sub(self.hi, self.lo)
    }
}

impl Shape {
    /// The exact bounding box (for cones, of the two rim circles).
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        match self {
            Shape::Sphere { center, radius } => {
                b.grow(sub(*center, [*radius; 3]));
                b.grow(add(*center, [*radius; 3]));
            }
            Shape::Cone {
                base,
                base_radius,
                apex,
                apex_radius,
            } => {
                // A circle of radius r about unit axis u extends r*sqrt(1-u_i^2) along axis i.
                let u = ConeFrame::new(*base, *base_radius, *apex, *apex_radius).axis;
                let ext = |r: f64| -> V3 {
                    let e = |ui: f64| r * (1.0 - ui * ui).max(0.0).sqrt();
                    [e(u[0]), e(u[1]), e(u[2])]
                };
                for (c, r) in [(*base, *base_radius), (*apex, *apex_radius)] {
                    let e = ext(r);
                    b.grow(sub(c, e));
                    b.grow(add(c, e));
                }
            }
            Shape::Polygon { vertices } => vertices.iter().for_each(|v| b.grow(*v)),
            Shape::Patch { vertices, .. } => vertices.iter().for_each(|v| b.grow(*v)),
        }
        b
    }

    /// Unit normal of a planar shape's plane (polygons and patches), from
    /// its first three vertices.
    pub fn plane_normal(&self) -> Option<V3> {
        let v: &[V3] = match self {
            Shape::Polygon { vertices } => vertices,
            Shape::Patch { vertices, .. } => vertices,
            _ => return None,
        };
        Some(normalize(cross(sub(v[1], v[0]), sub(v[2], v[1]))))
    }
}
