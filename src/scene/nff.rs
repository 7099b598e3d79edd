//! Eric Haines' Neutral File Format writer, for inspecting a generated scene
//! with other tools.

use super::{Scene, Shape};
use crate::error::{Error, Result};
use crate::frame::write_atomically;
use glam::DVec3;
use std::fmt::Write as _;
use std::path::Path;

fn v(p: DVec3) -> String {
    format!("{} {} {}", p.x, p.y, p.z)
}

pub(super) fn write(scene: &Scene, path: &Path) -> Result<()> {
    let mut s = String::new();
    let w = &scene.view;
    let _ = writeln!(s, "# SPD {} at size factor {}", scene.kind, scene.size_factor);
    let _ = writeln!(
        s,
        "v\nfrom {}\nat {}\nup {}\nangle {}\nhither {}\nresolution {} {}",
        v(w.from),
        v(w.at),
        v(w.up),
        w.fov_deg,
        w.hither,
        w.resolution,
        w.resolution
    );
    let _ = writeln!(s, "b {}", v(scene.background));
    for l in &scene.lights {
        let _ = writeln!(s, "l {}", v(*l));
    }
    let mut current = u32::MAX;
    for o in &scene.objects {
        if o.material != current {
            current = o.material;
            let m = &scene.materials[current as usize];
            let _ = writeln!(
                s,
                "f {} {} {} {} {} {}",
                v(m.color),
                m.kd,
                m.ks,
                m.shine,
                m.transmit,
                m.ior
            );
        }
        match &o.shape {
            Shape::Sphere { center, radius } => {
                let _ = writeln!(s, "s {} {}", v(*center), radius);
            }
            Shape::Cone {
                base,
                base_radius,
                apex,
                apex_radius,
            } => {
                let _ = writeln!(s, "c\n{} {}\n{} {}", v(*base), base_radius, v(*apex), apex_radius);
            }
            Shape::Polygon { vertices } => {
                let _ = writeln!(s, "p {}", vertices.len());
                for p in vertices {
                    let _ = writeln!(s, "{}", v(*p));
                }
            }
            Shape::Patch { vertices, normals } => {
                let _ = writeln!(s, "pp 3");
                for (p, n) in vertices.iter().zip(normals) {
                    let _ = writeln!(s, "{} {}", v(*p), v(*n));
                }
            }
        }
    }
    write_atomically(path, |tmp| {
        std::fs::write(tmp, s.as_bytes()).map_err(|e| Error::io(path, e))
    })
}
