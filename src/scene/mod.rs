//! Surface scenes for the octree benchmarks: Eric Haines' Standard Procedural
//! Databases (SPD), generated from their published definitions. A scene is
//! only what the ray tracer needs: primitives (sphere, cone/cylinder, polygon,
//! smooth triangle), their materials, point lights and the SPD view.

mod balls;
mod gears;
mod lattice;
pub mod math;
mod mount;
mod nff;
mod rings;
pub mod shape;
mod teapot;
mod tetra;
mod tree;

use crate::error::{Error, Result};
use glam::DVec3;
pub use shape::{Aabb, ConeFrame, Shape};
use std::fmt;
use std::str::FromStr;

/// The eight SPD scenes Havran's octree comparison uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SpdScene {
    Balls,
    Gears,
    Lattice,
    Mount,
    Rings,
    Teapot,
    Tetra,
    Tree,
}

impl SpdScene {
    pub const ALL: [SpdScene; 8] = [
        SpdScene::Balls,
        SpdScene::Gears,
        SpdScene::Lattice,
        SpdScene::Mount,
        SpdScene::Rings,
        SpdScene::Teapot,
        SpdScene::Tetra,
        SpdScene::Tree,
    ];

    pub fn name(self) -> &'static str {
        match self {
            SpdScene::Balls => "balls",
            SpdScene::Gears => "gears",
            SpdScene::Lattice => "lattice",
            SpdScene::Mount => "mount",
            SpdScene::Rings => "rings",
            SpdScene::Teapot => "teapot",
            SpdScene::Tetra => "tetra",
            SpdScene::Tree => "tree",
        }
    }

    /// The size factor of the SPD's default size (the teapot at 12, the
    /// size Havran and the SPD table use, not the generator's 6).
    pub fn default_size(self) -> u32 {
        match self {
            SpdScene::Balls | SpdScene::Gears => 4,
            SpdScene::Lattice | SpdScene::Teapot => 12,
            SpdScene::Mount | SpdScene::Tetra => 6,
            SpdScene::Rings => 7,
            SpdScene::Tree => 11,
        }
    }

    /// Size factors the generator supports (beyond these, counts explode or
    /// the definition breaks down: mount's hash needs SF <= 7).
    pub fn size_range(self) -> (u32, u32) {
        match self {
            SpdScene::Balls => (1, 5),
            SpdScene::Gears => (1, 8),
            SpdScene::Lattice => (1, 40),
            SpdScene::Mount => (1, 7),
            SpdScene::Rings => (1, 20),
            SpdScene::Teapot => (2, 32),
            SpdScene::Tetra => (1, 8),
            SpdScene::Tree => (1, 16),
        }
    }
}

impl fmt::Display for SpdScene {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SpdScene {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        SpdScene::ALL.into_iter().find(|k| k.name() == s).ok_or_else(|| {
            Error::invalid(
                "scene",
                s,
                "expected one of balls, gears, lattice, mount, rings, teapot, tetra, tree",
            )
        })
    }
}

/// NFF surface: `kd` diffuse, `ks` mirror reflection (and highlight),
/// `shine` Phong exponent, `transmit` and `ior` refraction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub color: DVec3,
    pub kd: f64,
    pub ks: f64,
    pub shine: f64,
    pub transmit: f64,
    pub ior: f64,
}

impl Material {
    /// As the SPD library defines a surface: `half_angle_deg` is the angle at
    /// which the highlight falls to half strength, turned into a Phong
    /// exponent as the NFF output does.
    pub fn new(color: DVec3, kd: f64, ks: f64, half_angle_deg: f64, transmit: f64, ior: f64) -> Material {
        let a = half_angle_deg.to_radians();
        let shine = if a <= 0.0 {
            100000.0
        } else if a >= std::f64::consts::FRAC_PI_2 {
            1.0
        } else {
            0.5f64.ln() / a.cos().ln()
        };
        Material {
            color,
            kd,
            ks,
            shine,
            transmit,
            ior,
        }
    }
}

/// One object of a scene: its shape and material index.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    pub shape: Shape,
    pub material: u32,
}

/// The SPD view: `fov_deg` is the full angle between the centres of the
/// image's outer pixel rows; intersections nearer than `hither` are ignored.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub from: DVec3,
    pub at: DVec3,
    pub up: DVec3,
    pub fov_deg: f64,
    pub hither: f64,
    pub resolution: u32,
}

/// An SPD scene (Haines' procedural database): view, lights, materials and
/// objects.
#[derive(Clone, Debug)]
pub struct Scene {
    pub kind: SpdScene,
    pub size_factor: u32,
    pub view: View,
    pub lights: Vec<DVec3>,
    pub background: DVec3,
    pub materials: Vec<Material>,
    pub objects: Vec<Object>,
}

/// Primitive counts by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    pub spheres: usize,
    pub cones: usize,
    pub polygons: usize,
    pub patches: usize,
}

impl Counts {
    pub fn total(&self) -> usize {
        self.spheres + self.cones + self.polygons + self.patches
    }
}

impl fmt::Display for Counts {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} primitives: {} spheres, {} cylinders/cones, {} polygons, {} smooth triangles",
            self.total(),
            self.spheres,
            self.cones,
            self.polygons,
            self.patches
        )
    }
}

impl Scene {
    /// Generates `kind` at `size_factor` (None: the default size).
    pub fn generate(kind: SpdScene, size_factor: Option<u32>) -> Result<Scene> {
        let sf = size_factor.unwrap_or(kind.default_size());
        let (lo, hi) = kind.size_range();
        if sf < lo || sf > hi {
            return Err(Error::invalid(
                "size factor",
                sf.to_string(),
                format!("{kind} supports {lo}..={hi}"),
            ));
        }
        let mut b = Builder::default();
        let (view, lights) = match kind {
            SpdScene::Balls => balls::generate(&mut b, sf),
            SpdScene::Gears => gears::generate(&mut b, sf),
            SpdScene::Lattice => lattice::generate(&mut b, sf),
            SpdScene::Mount => mount::generate(&mut b, sf),
            SpdScene::Rings => rings::generate(&mut b, sf),
            SpdScene::Teapot => teapot::generate(&mut b, sf),
            SpdScene::Tetra => tetra::generate(&mut b, sf),
            SpdScene::Tree => tree::generate(&mut b, sf),
        };
        Ok(Scene {
            kind,
            size_factor: sf,
            view,
            lights,
            background: DVec3::new(0.078, 0.361, 0.753),
            materials: b.materials,
            objects: b.objects,
        })
    }

    pub fn counts(&self) -> Counts {
        let mut c = Counts::default();
        for o in &self.objects {
            match o.shape {
                Shape::Sphere { .. } => c.spheres += 1,
                Shape::Cone { .. } => c.cones += 1,
                Shape::Polygon { .. } => c.polygons += 1,
                Shape::Patch { .. } => c.patches += 1,
            }
        }
        c
    }

    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for o in &self.objects {
            b.union(&o.shape.bounds());
        }
        b
    }

    /// Only the teapot is double sided in the SPD's testing procedure.
    pub fn double_sided(&self) -> bool {
        self.kind == SpdScene::Teapot
    }

    /// Writes the scene in Eric Haines' Neutral File Format.
    pub fn write_nff(&self, path: &std::path::Path) -> Result<()> {
        nff::write(self, path)
    }
}

/// Collects objects under the current material, as the SPD library does.
#[derive(Default)]
pub(crate) struct Builder {
    materials: Vec<Material>,
    objects: Vec<Object>,
}

impl Builder {
    fn material(&mut self, m: Material) {
        self.materials.push(m);
    }

    fn push(&mut self, shape: Shape) {
        // Every generator sets a material before its first object (the
        // generators are fixed code, not input).
        #[allow(clippy::expect_used)]
        let material = self
            .materials
            .len()
            .checked_sub(1)
            .expect("a material before any object") as u32;
        self.objects.push(Object { shape, material });
    }

    fn sphere(&mut self, center: DVec3, radius: f64) {
        self.push(Shape::Sphere { center, radius });
    }

    fn cone(&mut self, base: DVec3, base_radius: f64, apex: DVec3, apex_radius: f64) {
        self.push(Shape::Cone {
            base,
            base_radius,
            apex,
            apex_radius,
        });
    }

    fn polygon(&mut self, vertices: Vec<DVec3>) {
        self.push(Shape::Polygon { vertices });
    }
}

fn view(from: DVec3, at: DVec3, up: DVec3, fov_deg: f64, hither: f64) -> View {
    View {
        from,
        at,
        up,
        fov_deg,
        hither,
        resolution: 512,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn counts(kind: SpdScene) -> Counts {
        Scene::generate(kind, None).unwrap().counts()
    }

    #[test]
    fn default_sizes_have_the_published_primitive_counts() {
        let c = |spheres, cones, polygons, patches| Counts {
            spheres,
            cones,
            polygons,
            patches,
        };
        assert_eq!(counts(SpdScene::Balls), c(7381, 0, 1, 0));
        assert_eq!(counts(SpdScene::Gears), c(0, 0, 9345, 0));
        assert_eq!(counts(SpdScene::Lattice), c(2197, 6084, 0, 0));
        assert_eq!(counts(SpdScene::Mount), c(4, 0, 8192, 0));
        assert_eq!(counts(SpdScene::Rings), c(4200, 4200, 1, 0));
        assert_eq!(counts(SpdScene::Teapot), c(0, 0, 144, 9120));
        assert_eq!(counts(SpdScene::Tetra), c(0, 0, 4096, 0));
        assert_eq!(counts(SpdScene::Tree), c(4095, 4095, 1, 0));
    }

    #[test]
    fn bounding_boxes_match_the_published_sizes() {
        let size = |k| Scene::generate(k, None).unwrap().bounds().size();
        let close = |a: DVec3, b: DVec3, tol: f64| (a - b).abs().cmple(DVec3::splat(tol)).all();
        assert!(
            close(size(SpdScene::Balls), DVec3::new(24.0, 24.0, 1.331), 2e-3),
            "{:?}",
            size(SpdScene::Balls)
        );
        assert!(close(size(SpdScene::Gears), DVec3::new(4.0, 4.0, 1.0), 1e-9));
        assert!(close(size(SpdScene::Lattice), DVec3::splat(1.0417), 1e-4));
        assert!(
            close(size(SpdScene::Mount), DVec3::new(2.160, 2.160, 2.081), 2e-3),
            "{:?}",
            size(SpdScene::Mount)
        );
        assert!(
            close(size(SpdScene::Rings), DVec3::new(19.678, 19.251, 19.678), 2e-3),
            "{:?}",
            size(SpdScene::Rings)
        );
        assert!(close(size(SpdScene::Teapot), DVec3::new(8.0, 8.0, 3.15), 1e-9));
        assert!(close(size(SpdScene::Tetra), DVec3::splat(2.0), 1e-12));
        assert!(
            close(size(SpdScene::Tree), DVec3::new(100.0, 100.0, 3.15), 0.02),
            "{:?}",
            size(SpdScene::Tree)
        );
    }

    #[test]
    fn gear_faces_are_concave_144_gons() {
        let s = Scene::generate(SpdScene::Gears, Some(1)).unwrap();
        let big: Vec<_> = s
            .objects
            .iter()
            .filter_map(|o| match &o.shape {
                Shape::Polygon { vertices } if vertices.len() > 4 => Some(vertices.len()),
                _ => None,
            })
            .collect();
        assert_eq!(big, vec![144, 144]);
    }

    #[test]
    fn out_of_range_sizes_are_refused() {
        let e = Scene::generate(SpdScene::Mount, Some(9)).unwrap_err();
        assert!(e.to_string().contains("mount supports 1..=7"), "{e}");
        assert!("teapots".parse::<SpdScene>().is_err());
    }
}
