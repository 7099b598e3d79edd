//! lacuna's structures, one line each: the one place a built-in structure
//! is registered. It sits above every structure (which know only
//! `method.rs`); the CLI, the bench and the tests iterate it.

use super::method::Accel;
use super::params::{Param, Params};
use super::{auto, distance, grid, hybrid, kd, lbvh, naive, octree};
use crate::error::{Error, Result};
use crate::spatial::Traversal;

/// Every structure, in the order the CLI and the bench list them.
pub const TABLE: &[Accel] = &[
    Accel(&naive::Naive),
    Accel(&lbvh::LbvhMethod),
    Accel(&grid::GridMethod),
    Accel(&distance::DistanceMethod { octants: false }),
    Accel(&distance::DistanceMethod { octants: true }),
    Accel(&kd::cpu::KdCpu),
    Accel(&kd::gpu::KdGpu),
    Accel(&hybrid::HybridMethod),
    Accel(&octree::OctreeMethod(Traversal::O84)),
    Accel(&octree::OctreeMethod(Traversal::O89)),
    Accel(&octree::OctreeMethod(Traversal::O93)),
    Accel(&octree::OctreeMethod(Traversal::Rev)),
    Accel(&auto::AutoMethod),
];

impl Accel {
    /// Naive marching, the reference every structure must equal.
    pub fn naive() -> Accel {
        naive::NAIVE
    }

    pub fn is_naive(self) -> bool {
        self == naive::NAIVE
    }

    /// The registered structures except naive.
    pub fn skipping() -> impl Iterator<Item = Accel> {
        TABLE.iter().copied().filter(|a| !a.is_naive())
    }

    /// The registered structure named `name`.
    pub fn find(name: &str) -> Option<Accel> {
        TABLE.iter().copied().find(|a| a.name() == name)
    }
}

impl std::str::FromStr for Accel {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Accel::find(s).ok_or_else(|| {
            let names: Vec<&str> = TABLE.iter().map(|a| a.name()).collect();
            Error::invalid("accel", s, format!("expected one of: {}", names.join(", ")))
        })
    }
}

/// A parameter as every structure in `accels` that has it declares it: the
/// kind and help are one; defaults may differ per structure.
#[derive(Clone, Debug)]
pub struct SharedParam {
    pub param: Param,
    /// (structure, its default), in table order.
    pub defaults: Vec<(Accel, String)>,
}

impl SharedParam {
    /// One line for `--help`: the help, the values, the defaults and the
    /// structures that read it.
    pub fn help(&self) -> String {
        let first = &self.defaults[0].1;
        let names: Vec<String> = self.defaults.iter().map(|(a, _)| a.to_string()).collect();
        if self.defaults.iter().all(|(_, d)| d == first) {
            format!(
                "{} [{}; default {first}; read by {}]",
                self.param.help,
                self.param.values(),
                names.join(", ")
            )
        } else {
            let defaults: Vec<String> = self.defaults.iter().map(|(a, d)| format!("{a} {d}")).collect();
            format!(
                "{} [{}; default: {}]",
                self.param.help,
                self.param.values(),
                defaults.join(", ")
            )
        }
    }
}

/// Every parameter of the structures in `accels`, once each, in the order
/// they first appear; a parameter two structures declare with different
/// kinds or help is an error naming both.
pub fn shared_params(accels: &[Accel]) -> Result<Vec<SharedParam>> {
    let mut out: Vec<SharedParam> = Vec::new();
    for &a in accels {
        for p in a.method().params() {
            match out.iter_mut().find(|s| s.param.name == p.name) {
                Some(s) => {
                    if s.param.kind != p.kind || s.param.help != p.help {
                        return Err(Error::invalid(
                            "parameter",
                            p.name,
                            format!(
                                "{} and {a} declare it differently (kind and help must agree)",
                                s.defaults[0].0
                            ),
                        ));
                    }
                    s.defaults.push((a, p.default.to_string()));
                }
                None => out.push(SharedParam {
                    param: *p,
                    defaults: vec![(a, p.default.to_string())],
                }),
            }
        }
    }
    Ok(out)
}

/// `accel`'s parameters from values given to every structure (the command
/// line's flags, a bench TOML's keys): each value is checked against the
/// parameter of its name, whichever structures have it (a name none has, or
/// a bad value, is an error), then `accel` takes those it has.
pub fn params_for(accel: Accel, given: &[(&str, &str)]) -> Result<Params> {
    let shared = shared_params(TABLE)?;
    let mut own = Vec::new();
    for &(name, text) in given {
        let param = shared
            .iter()
            .map(|s| s.param)
            .chain(accel.method().params().iter().copied())
            .find(|p| p.name == name)
            .ok_or_else(|| {
                let names: Vec<&str> = shared.iter().map(|s| s.param.name).collect();
                Error::invalid(
                    "parameter",
                    name,
                    format!("no structure has it (parameters: {})", names.join(", ")),
                )
            })?;
        param.parse(text)?;
        if accel.method().params().iter().any(|p| p.name == name) {
            own.push((name, text));
        }
    }
    accel.params(&own)
}
