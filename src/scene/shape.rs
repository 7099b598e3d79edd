//! The primitive kinds the SPD scenes contain, and their exact bounding boxes.

use super::math::normalize;
use glam::DVec3;

/// The shape of a scene object.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    Sphere {
        center: DVec3,
        radius: f64,
    },
    /// Open cylinder or cone (no caps) from `base` to `apex`.
    Cone {
        base: DVec3,
        base_radius: f64,
        apex: DVec3,
        apex_radius: f64,
    },
    /// Planar polygon, convex or concave; its first three vertices span a
    /// convex corner (the SPD guarantees it), which gives the plane.
    Polygon {
        vertices: Vec<DVec3>,
    },
    /// Triangle with per-vertex normals (smooth shaded, double sided).
    Patch {
        vertices: [DVec3; 3],
        normals: [DVec3; 3],
    },
}

/// An open cone's frame: unit axis from base to apex, height, and radius
/// slope (apex radius - base radius) / height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConeFrame {
    pub axis: DVec3,
    pub height: f64,
    pub slope: f64,
}

impl ConeFrame {
    pub fn new(base: DVec3, base_radius: f64, apex: DVec3, apex_radius: f64) -> ConeFrame {
        let d = apex - base;
        let height = d.length();
        ConeFrame {
            // d * (1 / height) as glam's normalize() does, but with the
            // length kept (and no fallback for a zero-length cone).
            axis: d * (1.0 / height),
            height,
            slope: (apex_radius - base_radius) / height,
        }
    }
}

/// Axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub lo: DVec3,
    pub hi: DVec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        lo: DVec3::INFINITY,
        hi: DVec3::NEG_INFINITY,
    };

    pub fn grow(&mut self, p: DVec3) {
        // f64::min and f64::max per component, not glam's min/max (a
        // comparison and select, which differ on NaN and on signed zeros).
        for a in 0..3 {
            self.lo[a] = self.lo[a].min(p[a]);
            self.hi[a] = self.hi[a].max(p[a]);
        }
    }

    pub fn union(&mut self, b: &Aabb) {
        self.grow(b.lo);
        self.grow(b.hi);
    }

    pub fn size(&self) -> DVec3 {
        self.hi - self.lo
    }
}

impl Shape {
    /// The exact bounding box (for cones, of the two rim circles).
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        match self {
            Shape::Sphere { center, radius } => {
                b.grow(*center - *radius);
                b.grow(*center + *radius);
            }
            Shape::Cone {
                base,
                base_radius,
                apex,
                apex_radius,
            } => {
                // A circle of radius r about unit axis u extends r*sqrt(1-u_i^2) along axis i.
                let u = ConeFrame::new(*base, *base_radius, *apex, *apex_radius).axis;
                let ext = |r: f64| u.map(|ui| r * (1.0 - ui * ui).max(0.0).sqrt());
                for (c, r) in [(*base, *base_radius), (*apex, *apex_radius)] {
                    let e = ext(r);
                    b.grow(c - e);
                    b.grow(c + e);
                }
            }
            Shape::Polygon { vertices } => vertices.iter().for_each(|v| b.grow(*v)),
            Shape::Patch { vertices, .. } => vertices.iter().for_each(|v| b.grow(*v)),
        }
        b
    }

    /// Unit normal of a planar shape's plane (polygons and patches), from
    /// its first three vertices.
    pub fn plane_normal(&self) -> Option<DVec3> {
        let v: &[DVec3] = match self {
            Shape::Polygon { vertices } => vertices,
            Shape::Patch { vertices, .. } => vertices,
            _ => return None,
        };
        Some(normalize((v[1] - v[0]).cross(v[2] - v[1])))
    }
}
