//! `kanegen show`: the validated model with units and readable numbers.

use std::fmt::Write as _;

use kanegen::model::{Base, Length, Model, ParamKind};

/// `v` with six significant digits, without trailing zeros: fixed notation from 10⁻⁴ to 10⁶,
/// scientific outside.
pub(crate) fn number(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let exponent = v.abs().log10().floor() as i32;
    if (-4..6).contains(&exponent) {
        let decimals = (5 - exponent).max(0) as usize;
        let s = format!("{v:.decimals$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.')
        } else {
            &s
        };
        s.to_owned()
    } else {
        format!("{v:.5e}")
    }
}

/// The unit of parameter `id` of `model` (SI).
pub(crate) fn unit(model: &Model, id: usize) -> &'static str {
    let p = &model.params[id];
    if let Base::Wheeled(w) = &model.base {
        if id == w.radius || id == w.track {
            return "m";
        }
        if id == w.wheel_mass {
            return "kg";
        }
        if id == w.wheel_axle_inertia || id == w.wheel_diametral_inertia {
            return "kg·m²";
        }
    }
    let body = model
        .links
        .iter()
        .filter_map(|l| l.body.as_ref())
        .find(|b| b.mass == id || b.first_moment.contains(&id) || b.inertia.contains(&id));
    match (p.kind, body) {
        (ParamKind::Gravity, _) => "m/s²",
        (_, Some(b)) if b.mass == id => "kg",
        (_, Some(b)) if b.first_moment.contains(&id) => "kg·m",
        (_, Some(_)) => "kg·m²",
        _ => "m",
    }
}

/// What parameter `id` is, in words.
fn what(model: &Model, id: usize) -> &'static str {
    match (model.params[id].kind, unit(model, id)) {
        (ParamKind::Gravity, _) => "gravity",
        (ParamKind::Length, _) => "length",
        (ParamKind::Wheel, "m") if model.wheeled_base().is_some_and(|w| w.radius == id) => {
            "wheel radius"
        }
        (ParamKind::Wheel, "m") => "track width",
        (ParamKind::Wheel, "kg") => "wheel mass",
        (ParamKind::Wheel, _)
            if model
                .wheeled_base()
                .is_some_and(|w| w.wheel_axle_inertia == id) =>
        {
            "wheel inertia about the axle"
        }
        (ParamKind::Wheel, _) => "wheel inertia about a diameter",
        (_, "kg") => "mass",
        (_, "kg·m") => "first moment m·S",
        _ => "inertia about the frame origin",
    }
}

fn length(s: &Length, m: &Model) -> String {
    match s.symbol {
        None => number(s.coef),
        Some(p) if s.coef == 1.0 => m.params[p].name.clone(),
        Some(p) if s.coef == -1.0 => format!("-{}", m.params[p].name),
        Some(p) => format!("{}·{}", number(s.coef), m.params[p].name),
    }
}

fn axis(a: [f64; 3]) -> String {
    format!("[{}, {}, {}]", number(a[0]), number(a[1]), number(a[2]))
}

/// The frame tree: each frame under its parent, with its joint and body.
fn frames(m: &Model, s: &mut String) {
    let _ = writeln!(s, "frames ({}), translations P in m:", m.links.len());
    for i in m.preorder() {
        let l = &m.links[i];
        let indent = "  ".repeat(m.path_to_base(i).count() + 1);
        let _ = write!(s, "{indent}{}", l.name);
        if let Some(j) = l.joint() {
            let t: Vec<String> = j.translation.iter().map(|x| length(x, m)).collect();
            let _ = write!(
                s,
                " <- {} `{}` axis {} P [{}]",
                j.kind.name().to_lowercase(),
                j.name,
                axis(j.axis),
                t.join(", ")
            );
            if let Some(sp) = j.speed() {
                let _ = write!(s, ", speed {}", m.speeds[sp].name);
            }
        }
        if let Some(b) = &l.body {
            let _ = write!(
                s,
                "  [body {}: m = {} kg]",
                b.name,
                number(m.params[b.mass].value)
            );
        }
        let _ = writeln!(s);
    }
}

/// Whether speed `i` is a linear one (a prismatic joint's, or the wheeled base's ẋ).
fn speed_is_linear(m: &Model, i: usize) -> bool {
    m.wheeled_base().is_some_and(|w| w.x_speed == i)
        || m.links
            .iter()
            .filter_map(|l| l.joint())
            .any(|j| matches!(j.kind, kanegen::model::JointKind::Prismatic { speed } if speed == i))
}

/// The text of `kanegen show`.
pub(crate) fn model(m: &Model) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "model {} ({})", m.name, m.source);
    if !m.description.is_empty() {
        let _ = writeln!(s, "  {}", m.description);
    }
    match &m.base {
        Base::Fixed => {
            let _ = writeln!(s, "base: fixed frame `{}`", m.links[0].name);
        }
        Base::Wheeled(w) => {
            let _ = writeln!(
                s,
                "base: two-wheeled heading frame `{}`, speeds {} (m/s) and {} (rad/s)",
                m.links[0].name, m.speeds[w.x_speed].name, m.speeds[w.psi_speed].name
            );
        }
        Base::Floating => {
            let _ = writeln!(
                s,
                "base: floating frame `{}`, coordinates {} (position in the world, quaternion base → world), speeds {} (linear and angular velocity in the base frame)",
                m.links[0].name,
                m.coordinate_names()[..7].join(", "),
                m.speeds[..6]
                    .iter()
                    .map(|s| s.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
    }
    let g = &m.gravity;
    let _ = writeln!(
        s,
        "gravity: {} = {} m/s² along {} in the {} frame",
        m.params[g.symbol].name,
        number(m.params[g.symbol].value),
        axis(g.direction),
        if m.is_floating() { "world" } else { "base" }
    );
    frames(m, &mut s);
    let _ = writeln!(s, "speeds ({}):", m.independent_dof());
    for (i, sp) in m.speeds.iter().enumerate() {
        if let Some(mm) = m.mimic_of(i) {
            let _ = writeln!(
                s,
                "  mimic: {} = {} · {} {} {} (dependent, not an input)",
                sp.coordinate,
                number(mm.multiplier),
                m.speeds[mm.master].coordinate,
                if mm.offset < 0.0 { '-' } else { '+' },
                number(mm.offset.abs())
            );
            continue;
        }
        if m.is_floating() && i < 6 {
            let (what, u) = if i < 3 {
                ("linear velocity", "m/s")
            } else {
                ("angular velocity", "rad/s")
            };
            let _ = writeln!(
                s,
                "  u[{i:2}] = {} in {u} (base {what}, base frame)",
                sp.name
            );
            continue;
        }
        let (q, u) = if speed_is_linear(m, i) {
            ("m", "m/s")
        } else {
            ("rad", "rad/s")
        };
        let _ = writeln!(
            s,
            "  u[{i:2}] = {} in {u} (rate of {} in {q})",
            sp.name, sp.coordinate
        );
    }
    let width = m.params.iter().map(|p| p.name.len()).max().unwrap_or(0);
    let _ = writeln!(
        s,
        "parameters ({}), 6 significant digits (the model file has the exact values):",
        m.params.len()
    );
    for (id, p) in m.params.iter().enumerate() {
        let _ = writeln!(
            s,
            "  {:<width$} = {:>12} {:<6} {}",
            p.name,
            number(p.value),
            unit(m, id),
            what(m, id)
        );
    }
    s
}
