//! Regressors: `τ = Y(q, u, u̇) π` and `g = Y_g(q) β`, and their base (identifiable) parameters.
//!
//! The dynamics are linear in the inertial parameters: body k enters only through its mass,
//! first moment and inertia about its frame origin (Khalil's standard parameters), each of which
//! the recursion uses linearly (body inertia forces, composite sums), and the wheels through
//! `2 mw + 2 YYw / R²` and `mw L²/2 + YYw L²/(2R²) + 2 ZZw` (linear in `mw`, `YYw`, `ZZw`; the
//! radius `R` and track `L` are geometry and stay parameters of Y, like the lengths and `g`).
//! So every column of Y is the exact derivative `∂τ/∂π_p` ([`Arena::diff`]) and contains no
//! inertial parameter; with baked parameters the inertial parameters are kept as symbols for
//! this derivation only (they vanish from Y).
//!
//! Base parameters are found numerically: the regressors of random states are stacked and the
//! columns taken in the order of π (root to leaves, each body's `m, MX, … ZZ`): a column whose
//! residual after projection on the columns kept so far (Gram–Schmidt, reorthogonalised) is
//! below `1e-8` of its norm depends on them. The coefficients of each dependency come from the
//! triangular factor; they group the dependent parameter into the kept ones, the way Khalil's
//! rules do (`XXR4l = XX4l − YY4l`, the mass and axial first moment of a body into its parent).
//! The grouping is then checked on other random states. The coefficients are numbers: they hold
//! for the model's geometry (its lengths), which identification does not change.

use kanegen_model::{Model, ParamKind};

use super::ctx::Ctx;
use super::grouping::{Exactness, SymbolicGroup};
use super::regressor_sample::{Rng, regressor_at};
use crate::expr::{Arena, ExprId, Wrt};

/// Which model parameters the regressors' columns stand for, and the base parameters found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Regressors {
    /// π: model parameter indices, per body in link order `m, MX, MY, MZ, XX, XY, XZ, YY, YZ,
    /// ZZ`, then a wheeled base's `mw, YYw, ZZw`.
    pub inertial: Vec<usize>,
    /// β: model parameter indices, per body `m, MX, MY, MZ`.
    pub beta: Vec<usize>,
    /// Base parameters of the inverse-dynamics regressor (when a base function is derived).
    pub base: Option<BaseParameters>,
    /// Base parameters of the gravity regressor (when its base function is derived).
    pub base_beta: Option<BaseParameters>,
}

/// The identifiable combinations of a regressor's parameters.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BaseParameters {
    /// Names, Khalil's style: the kept parameter's symbol, with `R` after its kind prefix when
    /// others are grouped into it (`XXR4l`).
    pub names: Vec<String>,
    /// Per base parameter: `(index into the full parameter vector, coefficient)`, the kept
    /// parameter first with coefficient 1.
    pub groups: Vec<Vec<(usize, f64)>>,
    /// Indices (into the full vector) of parameters with no effect at all (zero columns).
    pub unidentifiable: Vec<usize>,
    /// Number of random states stacked.
    pub states: usize,
    /// Largest relative residual of the grouping `Y_D − Y_I C` on other random states.
    pub check_residual: f64,
    /// The same groups with their coefficients as exact expressions of the geometry (lengths,
    /// wheel radius and track; numbers where none enters), parallel to `groups`
    /// (`super::grouping`).
    pub symbolic: Vec<SymbolicGroup>,
    /// How the symbolic groups were verified.
    pub exactness: Exactness,
}

impl Regressors {
    /// π and β of `model` (no base parameters).
    pub fn of(model: &Model) -> Self {
        layout(model)
    }
}

impl BaseParameters {
    /// The base parameters' values from the full parameter vector.
    pub fn values(&self, full: &[f64]) -> Vec<f64> {
        self.groups
            .iter()
            .map(|g| g.iter().map(|&(i, c)| c * full[i]).sum())
            .collect()
    }
}

/// π and β of `model`.
pub fn layout(model: &Model) -> Regressors {
    let mut inertial = Vec::new();
    let mut beta = Vec::new();
    for b in model.links.iter().filter_map(|l| l.body.as_ref()) {
        inertial.push(b.mass);
        inertial.extend(b.first_moment);
        inertial.extend(b.inertia);
        beta.push(b.mass);
        beta.extend(b.first_moment);
    }
    if let Some(w) = model.wheeled_base() {
        inertial.extend([
            w.wheel_mass,
            w.wheel_axle_inertia,
            w.wheel_diametral_inertia,
        ]);
    }
    Regressors {
        inertial,
        beta,
        base: None,
        base_beta: None,
    }
}

/// Whether parameter `p` of `model` is one of the regressor parameters (kept symbolic in the
/// regressors' derivation even when the others are baked).
pub(super) fn is_regression_param(model: &Model, p: usize) -> bool {
    if model.params[p].kind == ParamKind::Inertial {
        return true;
    }
    model.wheeled_base().is_some_and(|w| {
        [
            w.wheel_mass,
            w.wheel_axle_inertia,
            w.wheel_diametral_inertia,
        ]
        .contains(&p)
    })
}

impl Ctx<'_> {
    /// Y: `(row, col, ∂τ_row/∂π_col)`.
    pub(super) fn inertial_regressor(&mut self, pi: &[usize]) -> Vec<(usize, usize, ExprId)> {
        let keep = std::mem::replace(&mut self.keep_inertial, true);
        let tau = self.rnea(true, true);
        self.keep_inertial = keep;
        self.columns(&tau, pi, "Y")
    }

    /// Y_g: `(row, col, ∂g_row/∂β_col)`.
    pub(super) fn gravity_regressor(&mut self, beta: &[usize]) -> Vec<(usize, usize, ExprId)> {
        let keep = std::mem::replace(&mut self.keep_inertial, true);
        let comp = self.composites(false, None);
        let g = self.gravity(&comp);
        self.keep_inertial = keep;
        self.columns(&g, beta, "Yg")
    }

    fn columns(
        &mut self,
        v: &[ExprId],
        params: &[usize],
        label: &str,
    ) -> Vec<(usize, usize, ExprId)> {
        let mut out = Vec::new();
        for (col, &p) in params.iter().enumerate() {
            for (row, &e) in v.iter().enumerate() {
                let d = self.ar.diff(e, Wrt::Param(p as u32));
                if self.ar.is_zero(d) {
                    continue;
                }
                let d = if self.ar.hoist_params {
                    self.ar.hoist(d, &format!("{label}[{row},{col}]"))
                } else {
                    d
                };
                out.push((row, col, d));
            }
        }
        out
    }
}

/// The base parameters of the regressor `entries` (columns: the model parameters `params`).
pub(super) fn base_parameters(
    ar: &Arena,
    model: &Model,
    entries: &[(usize, usize, ExprId)],
    params: &[usize],
    baked: bool,
) -> BaseParameters {
    let n = model.independent_dof().max(1);
    let cols = params.len();
    let states = (3 * cols / n + 10).max(30);
    let values: Vec<f64> = model.params.iter().map(|p| p.value).collect();
    let roots: Vec<ExprId> = entries.iter().map(|&(_, _, e)| e).collect();
    let needed = ar.needed_nodes(&roots);
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    // Column-major stack of `states` regressors.
    let rows = states * n;
    let mut a = vec![vec![0.0; rows]; cols];
    for s in 0..states {
        let y = regressor_at(ar, entries, model, &values, &needed, cols, &mut rng);
        for r in 0..n {
            for c in 0..cols {
                a[c][s * n + r] = y[r * cols + c];
            }
        }
    }
    // Gram–Schmidt in the order of the parameters, reorthogonalised.
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let mut kept: Vec<usize> = Vec::new();
    // r[k]: coefficients of kept column k on basis vectors 0..=k.
    let mut r: Vec<Vec<f64>> = Vec::new();
    let mut dependent: Vec<(usize, Vec<f64>)> = Vec::new();
    let mut unidentifiable = Vec::new();
    let max_norm = a.iter().map(|c| dot(c, c).sqrt()).fold(0.0, f64::max);
    for (c, col) in a.iter().enumerate() {
        let norm = dot(col, col).sqrt();
        if norm <= 1e-12 * max_norm.max(1e-300) {
            unidentifiable.push(c);
            continue;
        }
        let mut res = col.clone();
        let mut h = vec![0.0; basis.len()];
        for _ in 0..2 {
            for (k, b) in basis.iter().enumerate() {
                let x = dot(b, &res);
                h[k] += x;
                res.iter_mut().zip(b).for_each(|(v, bv)| *v -= x * bv);
            }
        }
        let rn = dot(&res, &res).sqrt();
        if rn <= 1e-8 * norm {
            dependent.push((c, h));
        } else {
            res.iter_mut().for_each(|v| *v /= rn);
            let mut rk = h;
            rk.push(rn);
            r.push(rk);
            basis.push(res);
            kept.push(c);
        }
    }
    // Coefficients: R c = h, back substitution.
    let mut groups: Vec<Vec<(usize, f64)>> = kept.iter().map(|&k| vec![(k, 1.0)]).collect();
    let mut coefficients: Vec<(usize, Vec<f64>)> = Vec::new();
    for (c, h) in dependent {
        // Only the columns kept before `c` take part.
        let b = h.len();
        let mut x = vec![0.0; b];
        for i in (0..b).rev() {
            let mut s = h[i];
            for j in i + 1..b {
                s -= r[j][i] * x[j];
            }
            x[i] = s / r[i][i];
        }
        // Snap rounding noise: exact zeros and integers stay exact.
        let scale = a[c].iter().map(|v| v.abs()).fold(0.0, f64::max).max(1e-300);
        for (i, xi) in x.iter_mut().enumerate() {
            let colmax = a[kept[i]].iter().map(|v| v.abs()).fold(0.0, f64::max);
            if (*xi * colmax).abs() <= 1e-11 * scale {
                *xi = 0.0;
            } else if (*xi - xi.round()).abs() <= 1e-10 * xi.abs().max(1.0) {
                *xi = xi.round();
            } else if let Ok(short) = format!("{xi:.11e}").parse::<f64>() {
                // 12 significant digits when that is the same number to rounding (lengths
                // such as 0.091 come back as 0.09100000000000001).
                if (short - *xi).abs() <= 1e-13 * xi.abs() {
                    *xi = short;
                }
            }
        }
        for (i, &xi) in x.iter().enumerate() {
            if xi != 0.0 {
                groups[i].push((c, xi));
            }
        }
        coefficients.push((c, x));
    }
    // Check the grouping on other states: Y_D = Y_I C.
    let mut worst: f64 = 0.0;
    for _ in 0..10 {
        let y = regressor_at(ar, entries, model, &values, &needed, cols, &mut rng);
        for row in 0..n {
            let yr = &y[row * cols..(row + 1) * cols];
            let scale = yr.iter().map(|v| v.abs()).fold(1e-300, f64::max);
            for (c, x) in &coefficients {
                let fit: f64 = kept.iter().zip(x).map(|(&k, xi)| yr[k] * xi).sum();
                worst = worst.max((yr[*c] - fit).abs() / scale);
            }
            for &c in &unidentifiable {
                worst = worst.max(yr[c].abs() / scale);
            }
        }
    }
    let names = groups
        .iter()
        .map(|g| {
            let name = &model.params[params[g[0].0]].name;
            if g.len() > 1 {
                grouped_name(name)
            } else {
                name.clone()
            }
        })
        .collect();
    let dependent: Vec<usize> = coefficients.iter().map(|(c, _)| *c).collect();
    let (symbolic, exactness) = super::grouping::symbolic(
        &super::grouping::Problem {
            ar,
            model,
            entries,
            params,
            kept: &kept,
            dependent: &dependent,
            unidentifiable: &unidentifiable,
            baked,
            needed: &needed,
        },
        &groups,
    );
    BaseParameters {
        names,
        groups,
        unidentifiable,
        states,
        check_residual: worst,
        symbolic,
        exactness,
    }
}

/// Khalil's name for a parameter with others grouped into it: `R` after the kind prefix
/// (`XX4l` → `XXR4l`, `m2` → `mR2`), else appended.
fn grouped_name(name: &str) -> String {
    const PREFIXES: [&str; 9] = ["MX", "MY", "MZ", "XX", "XY", "XZ", "YY", "YZ", "ZZ"];
    if let Some(p) = PREFIXES.iter().find(|p| name.starts_with(**p)) {
        format!("{p}R{}", &name[2..])
    } else if let Some(rest) = name.strip_prefix('m') {
        format!("mR{rest}")
    } else {
        format!("{name}R")
    }
}

/// `XXR2 = XX2 - YY3 + 0.25*m3` for listings.
pub fn group_text(model: &Model, params: &[usize], name: &str, group: &[(usize, f64)]) -> String {
    let mut s = format!("{name} =");
    for (k, &(i, c)) in group.iter().enumerate() {
        let pname = &model.params[params[i]].name;
        let sign = if c < 0.0 { "-" } else { "+" };
        let mag = c.abs();
        if k == 0 {
            s.push(' ');
            if c < 0.0 {
                s.push('-');
            }
        } else {
            s.push_str(&format!(" {sign} "));
        }
        if mag == 1.0 {
            s.push_str(pname);
        } else {
            s.push_str(&format!("{}*{pname}", crate::expr::fmt_num(mag)));
        }
    }
    s
}
