//! Structure parameters as schemas. Each structure declares its parameters
//! (`Method::params`): name, kind, default, help. The command line's flags
//! and `--help`, the bench TOML, the JSON records and the EXR metadata all
//! iterate the schemas; a structure reads its resolved values by name.
//!
//! Names are the command line's (`max-leaf`); the bench TOML writes them
//! with underscores (`max_leaf`). Two structures may share a parameter (the
//! macro-cell edge `cell`) with defaults of their own, but not its kind.

use crate::error::{Error, Result};
use std::fmt;

/// What values a parameter takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// An integer in `min..=max`, a power of two when `power_of_two`.
    Int { min: u32, max: u32, power_of_two: bool },
    /// `on` or `off` (TOML: also `true` or `false`).
    Switch,
    /// One of these words.
    Choice(&'static [&'static str]),
}

/// One parameter's value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Value {
    Int(u32),
    Switch(bool),
    Choice(&'static str),
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Int(n) => write!(f, "{n}"),
            Value::Switch(on) => f.write_str(if *on { "on" } else { "off" }),
            Value::Choice(w) => f.write_str(w),
        }
    }
}

/// A parameter of a structure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Param {
    pub name: &'static str,
    pub kind: Kind,
    pub default: Value,
    /// One line for `--help`.
    pub help: &'static str,
}

impl Param {
    pub const fn int(name: &'static str, default: u32, min: u32, max: u32, help: &'static str) -> Self {
        Param {
            name,
            kind: Kind::Int {
                min,
                max,
                power_of_two: false,
            },
            default: Value::Int(default),
            help,
        }
    }

    pub const fn power_of_two(name: &'static str, default: u32, min: u32, max: u32, help: &'static str) -> Self {
        Param {
            name,
            kind: Kind::Int {
                min,
                max,
                power_of_two: true,
            },
            default: Value::Int(default),
            help,
        }
    }

    pub const fn switch(name: &'static str, default: bool, help: &'static str) -> Self {
        Param {
            name,
            kind: Kind::Switch,
            default: Value::Switch(default),
            help,
        }
    }

    pub const fn choice(
        name: &'static str,
        words: &'static [&'static str],
        default: &'static str,
        help: &'static str,
    ) -> Self {
        Param {
            name,
            kind: Kind::Choice(words),
            default: Value::Choice(default),
            help,
        }
    }

    /// The same parameter with another default (a shared parameter whose
    /// default is the structure's own).
    pub const fn with_default(self, default: Value) -> Self {
        Param { default, ..self }
    }

    /// The values it takes, for `--help` and error messages.
    pub fn values(&self) -> String {
        match self.kind {
            Kind::Int {
                min,
                max: u32::MAX,
                power_of_two: false,
            } => format!("an integer >= {min}"),
            Kind::Int {
                min,
                max,
                power_of_two: false,
            } => format!("an integer in {min}..={max}"),
            Kind::Int { min, max, .. } => format!("a power of two in {min}..={max}"),
            Kind::Switch => "on or off".into(),
            Kind::Choice(words) => words.join(" or "),
        }
    }

    /// Parses `text` as this parameter's value.
    pub fn parse(&self, text: &str) -> Result<Value> {
        let bad = || Error::invalid(self.name, text, format!("expected {}", self.values()));
        match self.kind {
            Kind::Int { min, max, power_of_two } => {
                let n: u32 = text.trim().parse().map_err(|_| bad())?;
                if n < min || n > max || (power_of_two && !n.is_power_of_two()) {
                    return Err(bad());
                }
                Ok(Value::Int(n))
            }
            Kind::Switch => match text {
                "on" | "true" => Ok(Value::Switch(true)),
                "off" | "false" => Ok(Value::Switch(false)),
                _ => Err(bad()),
            },
            Kind::Choice(words) => words
                .iter()
                .find(|w| **w == text)
                .map(|w| Value::Choice(w))
                .ok_or_else(bad),
        }
    }
}

/// The values of one structure's parameters, in its schema's order, every
/// one set (defaults filled in).
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash)]
pub struct Params {
    values: Vec<(&'static str, Value)>,
}

impl Params {
    /// Every parameter of `schema` at its default.
    pub fn defaults(schema: &[Param]) -> Params {
        Params {
            values: schema.iter().map(|p| (p.name, p.default)).collect(),
        }
    }

    /// `schema`'s defaults with the `given` (name, text) values parsed in;
    /// a name `schema` does not have is an error listing the ones it has.
    pub fn resolve(schema: &[Param], given: &[(&str, &str)]) -> Result<Params> {
        let mut out = Self::defaults(schema);
        for (name, text) in given {
            let p = schema.iter().find(|p| p.name == *name).ok_or_else(|| {
                let names: Vec<&str> = schema.iter().map(|p| p.name).collect();
                let has = if names.is_empty() {
                    "none".to_string()
                } else {
                    names.join(", ")
                };
                Error::invalid(
                    "parameter",
                    *name,
                    format!("not a parameter of this structure (it has: {has})"),
                )
            })?;
            out.set(p.name, p.parse(text)?);
        }
        Ok(out)
    }

    /// Whether the structure has the parameter `name`.
    pub fn has(&self, name: &str) -> bool {
        self.values.iter().any(|(n, _)| *n == name)
    }

    fn set(&mut self, name: &str, value: Value) {
        if let Some(v) = self.values.iter_mut().find(|(n, _)| *n == name) {
            v.1 = value;
        }
    }

    pub fn get(&self, name: &str) -> Result<Value> {
        self.values
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| *v)
            .ok_or_else(|| Error::invalid("parameter", name, "is not a parameter of this structure"))
    }

    pub fn int(&self, name: &str) -> Result<u32> {
        match self.get(name)? {
            Value::Int(n) => Ok(n),
            v => Err(Error::invalid(
                "parameter",
                format!("{name} {v}"),
                "is not an integer parameter",
            )),
        }
    }

    pub fn switch(&self, name: &str) -> Result<bool> {
        match self.get(name)? {
            Value::Switch(on) => Ok(on),
            v => Err(Error::invalid(
                "parameter",
                format!("{name} {v}"),
                "is not an on/off parameter",
            )),
        }
    }

    pub fn choice(&self, name: &str) -> Result<&'static str> {
        match self.get(name)? {
            Value::Choice(w) => Ok(w),
            v => Err(Error::invalid(
                "parameter",
                format!("{name} {v}"),
                "is not a choice parameter",
            )),
        }
    }

    /// (name, value) pairs for printouts, EXR metadata and bench records.
    pub fn describe(&self) -> Vec<(&'static str, String)> {
        self.values.iter().map(|(n, v)| (*n, v.to_string())).collect()
    }

    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
}

impl fmt::Display for Params {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parts: Vec<String> = self.values.iter().map(|(n, v)| format!("{n} {v}")).collect();
        f.write_str(&parts.join(", "))
    }
}

/// The macro-cell edge of the structures that read cell ranges (their
/// defaults differ: `with_default`).
pub const CELL: Param = Param::power_of_two("cell", 16, 2, 256, "Macro-cell edge in voxels");

/// Cost-driven leaves for the trees (`accel::cost`): off reproduces the paper.
pub const COLLAPSE: Param = Param::switch(
    "collapse",
    false,
    "Cost-driven leaves: a subtree cheaper as one leaf by the measured cost model becomes one (on), or the paper's trees (off)",
);
