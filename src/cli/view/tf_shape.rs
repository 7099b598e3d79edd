//! A transfer function's shape as the viewer's arrow keys change it: a
//! ramp, band or spike window moved and widened, per channel where the
//! volume has several. Pure state.

/// How far one arrow key press moves or widens the TF window.
pub const TF_NUDGE: f32 = 0.02;

/// A transfer function the keys can reshape, or one they cannot (a JSON file).
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// `ramp`, `band` or `spike` with its two numbers and optional alpha.
    Window {
        kind: &'static str,
        a: f32,
        b: f32,
        alpha: Option<f32>,
    },
    /// One shape per channel (`A|B`): the arrows reshape every window.
    Channels(Vec<Shape>),
    /// Any other spec (a ParaView JSON path): switched to, not reshaped.
    Fixed(String),
}

impl Shape {
    pub fn parse(spec: &str) -> Shape {
        if spec.contains('|') {
            return Shape::Channels(spec.split('|').map(|s| Shape::parse(s.trim())).collect());
        }
        let parts: Vec<&str> = spec.split(':').collect();
        let num = |i: usize| parts.get(i).and_then(|s| s.parse::<f32>().ok());
        let kind = ["ramp", "band", "spike"].into_iter().find(|k| parts[0] == *k);
        match (kind, num(1), num(2), parts.len()) {
            (Some(kind), Some(a), Some(b), 3) => Shape::Window {
                kind,
                a,
                b,
                alpha: None,
            },
            (Some(kind), Some(a), Some(b), 4) if num(3).is_some() => Shape::Window {
                kind,
                a,
                b,
                alpha: num(3),
            },
            _ => Shape::Fixed(spec.to_string()),
        }
    }

    pub fn spec(&self) -> String {
        match self {
            Shape::Window { kind, a, b, alpha } => {
                let mut s = format!("{kind}:{a}:{b}");
                if let Some(alpha) = alpha {
                    s += &format!(":{alpha}");
                }
                s
            }
            Shape::Channels(shapes) => shapes.iter().map(Shape::spec).collect::<Vec<_>>().join("|"),
            Shape::Fixed(spec) => spec.clone(),
        }
    }

    /// Whether the arrows can reshape it: a window, or channels with one.
    pub fn reshapes(&self) -> bool {
        match self {
            Shape::Window { .. } => true,
            Shape::Channels(shapes) => shapes.iter().any(Shape::reshapes),
            Shape::Fixed(_) => false,
        }
    }

    /// Moves the window by `d` (a spike's centre; a ramp's or band's both ends).
    pub fn shift(&mut self, d: f32) {
        if let Shape::Channels(shapes) = self {
            shapes.iter_mut().for_each(|s| s.shift(d));
        }
        if let Shape::Window { kind, a, b, .. } = self {
            let round = |v: f32| (v * 1000.0).round() / 1000.0;
            *a = round(*a + d);
            if *kind != "spike" {
                *b = round(*b + d);
            }
        }
    }

    /// Widens the window by `d` (a spike's width; a ramp's or band's span, about its middle).
    pub fn widen(&mut self, d: f32) {
        if let Shape::Channels(shapes) = self {
            shapes.iter_mut().for_each(|s| s.widen(d));
        }
        if let Shape::Window { kind, a, b, .. } = self {
            let round = |v: f32| (v * 1000.0).round() / 1000.0;
            if *kind == "spike" {
                *b = round((*b + d).max(TF_NUDGE / 2.0));
            } else if *b - *a + 2.0 * d > TF_NUDGE {
                *a = round(*a - d);
                *b = round(*b + d);
            }
        }
    }
}
