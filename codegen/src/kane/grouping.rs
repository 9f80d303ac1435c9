//! The base parameters' groupings as exact expressions of the geometry, verified exactly.
//!
//! [`super::regressor::base_parameters`] finds which columns of a regressor depend on the ones
//! kept before them, and the coefficients, as numbers for the model file's geometry. Those
//! coefficients are functions of the geometric parameters: the lengths of the joint
//! translations, and for a wheeled base its radius `R` and track `L`. Khalil's closed-form rules
//! make them polynomials: a child's mass grouped into a parent's inertia comes with the square of
//! the distance between their origins (`XXR1 = XX1 + (L1² + L2²) m2`), a first moment with a
//! length, an inertia with a number; the wheels' axle inertia enters the base's mass as
//! `2 YYw / R²`.
//!
//! They are found here the way an experimenter would, then proven:
//!
//! 1. **Which geometry each coefficient depends on**: the coefficients are solved again (least
//!    squares on the kept columns of a stack of random states) with each geometric parameter
//!    changed by 30 %, one at a time.
//! 2. **Fit**: on random geometries (every geometric parameter scaled by a factor in
//!    `[0.5, 1.5]`), each coefficient is fitted by the monomials of the parameters it depends on:
//!    total degree ≤ 2 in the lengths (and the track), times `R^e`, `e ∈ −2..=2`; the fitted
//!    values are snapped to small rationals (denominators up to 12) and the fit must reproduce
//!    every sample to `1e-9`. A coefficient that does not fit keeps its number (reported).
//! 3. **Exact verification**: every dependency `Y_c = Σ_k x_k(geometry) Y_k` (and every column
//!    without effect, `Y_c = 0`) is evaluated in exact modular arithmetic
//!    ([`crate::expr::modular`]) at random points where *every* leaf is random, the geometry
//!    included, with `sin`/`cos` on the unit circle: an identity in q, u, u̇ and the geometry,
//!    not a numeric check at the model's values. Skipped (and reported) for baked parameters
//!    (the geometry is folded into rounded constants) and mimic models (dependent angles are
//!    not independent points of the circle).

use kanegen_model::{Model, ParamKind};

use super::regressor_sample::{Rng, regressor_at};
use crate::expr::modular::{self, ModValues};
use crate::expr::{Arena, ExprId};

/// A grouping coefficient as an exact expression of the geometry: `Σ value · Π param^power`
/// (model parameter indices; an empty product is the number itself).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Coefficient {
    /// `(value, [(model parameter, power)])`, powers non-zero, parameters sorted.
    pub terms: Vec<(f64, Vec<(usize, i32)>)>,
}

/// The result of the exact verification of a grouping.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Exactness {
    /// Random points at which every dependency was evaluated exactly (0: not checked).
    pub points: usize,
    /// Dependencies (grouped or without-effect columns) that hold exactly at every point.
    pub verified: usize,
    /// Dependencies checked.
    pub dependencies: usize,
    /// Names (full-vector parameter names) of the dependent parameters whose coefficients are
    /// numbers for the model's geometry only: the fit in the geometry failed, or the exact
    /// check did.
    pub numeric_only: Vec<String>,
    /// Why the exact check was skipped, if it was.
    pub skipped: Option<String>,
}

impl Coefficient {
    /// A plain number.
    pub fn number(v: f64) -> Self {
        Self {
            terms: if v == 0.0 {
                Vec::new()
            } else {
                vec![(v, Vec::new())]
            },
        }
    }

    /// Whether it is identically zero.
    pub fn is_zero(&self) -> bool {
        self.terms.is_empty()
    }

    /// Whether it is the number one.
    pub fn is_one(&self) -> bool {
        self.terms.len() == 1 && self.terms[0].0 == 1.0 && self.terms[0].1.is_empty()
    }

    /// Its value for the model parameter values `params`.
    pub fn eval(&self, params: &[f64]) -> f64 {
        self.terms
            .iter()
            .map(|(v, m)| v * m.iter().map(|&(p, e)| params[p].powi(e)).product::<f64>())
            .sum()
    }

    /// Its value modulo [`modular::P`] for the parameter values `params` in the field (`None`
    /// on a division by zero).
    pub fn eval_mod(&self, params: &[u64]) -> Option<u64> {
        let mut acc = 0;
        for (v, m) in &self.terms {
            let mut t = modular::from_f64(*v)?;
            for &(p, e) in m {
                let x = if e < 0 {
                    modular::inv(params[p])?
                } else {
                    params[p]
                };
                t = modular::mul(t, modular::pow(x, e.unsigned_abs() as u64));
            }
            acc = modular::add(acc, t);
        }
        Some(acc)
    }

    /// `L1^2 + L2^2`, `2/R^2`, `-0.5*L^2/R^2` (model parameter names).
    pub fn text(&self, model: &Model) -> String {
        if self.terms.is_empty() {
            return "0".into();
        }
        let mut s = String::new();
        for (i, (v, m)) in self.terms.iter().enumerate() {
            if i == 0 {
                if *v < 0.0 {
                    s.push('-');
                }
            } else {
                s.push_str(if *v < 0.0 { " - " } else { " + " });
            }
            s.push_str(&monomial_text(v.abs(), m, model));
        }
        s
    }
}

/// `0.5*L^2/R^2`.
fn monomial_text(v: f64, m: &[(usize, i32)], model: &Model) -> String {
    let power = |p: usize, e: i32| {
        let n = &model.params[p].name;
        if e == 1 {
            n.clone()
        } else {
            format!("{n}^{e}")
        }
    };
    let num: Vec<String> = m
        .iter()
        .filter(|(_, e)| *e > 0)
        .map(|&(p, e)| power(p, e))
        .collect();
    let den: Vec<String> = m
        .iter()
        .filter(|(_, e)| *e < 0)
        .map(|&(p, e)| power(p, -e))
        .collect();
    let mut s = String::new();
    if v != 1.0 || num.is_empty() {
        s.push_str(&crate::expr::fmt_num(v));
    }
    for n in num {
        if !s.is_empty() {
            s.push('*');
        }
        s.push_str(&n);
    }
    match den.len() {
        0 => {}
        1 => s.push_str(&format!("/{}", den[0])),
        _ => s.push_str(&format!("/({})", den.join("*"))),
    }
    s
}

/// A group's members with exact coefficients: `(index into the full vector, coefficient)`, the
/// kept parameter first with coefficient 1.
pub type SymbolicGroup = Vec<(usize, Coefficient)>;

/// `XXR1 = XX1 + (L1^2 + L2^2)*m2 - 2*MY2` for listings (`params`: the model parameters of the
/// full vector).
pub fn symbolic_group_text(
    model: &Model,
    params: &[usize],
    name: &str,
    group: &[(usize, Coefficient)],
) -> String {
    let mut s = format!("{name} =");
    for (k, (i, c)) in group.iter().enumerate() {
        let pname = &model.params[params[*i]].name;
        // One term with a negative sign: print it as a subtraction.
        let negative = c.terms.len() == 1 && c.terms[0].0 < 0.0;
        let c = if negative {
            Coefficient {
                terms: vec![(-c.terms[0].0, c.terms[0].1.clone())],
            }
        } else {
            c.clone()
        };
        if k == 0 {
            s.push_str(if negative { " -" } else { " " });
        } else {
            s.push_str(if negative { " - " } else { " + " });
        }
        if c.is_one() {
            s.push_str(pname);
        } else if c.terms.len() == 1 {
            s.push_str(&format!("{}*{pname}", c.text(model)));
        } else {
            s.push_str(&format!("({})*{pname}", c.text(model)));
        }
    }
    s
}

/// The geometric parameters of `model`: `(parameter, is a radius)`: the lengths, and a wheeled
/// base's track (polynomial) and radius (`R^e`, `e ∈ −2..=2`).
fn geometry(model: &Model) -> Vec<(usize, bool)> {
    let mut g: Vec<(usize, bool)> = model
        .params
        .iter()
        .enumerate()
        .filter(|(_, p)| p.kind == ParamKind::Length)
        .map(|(i, _)| (i, false))
        .collect();
    if let Some(w) = model.wheeled_base() {
        g.push((w.track, false));
        g.push((w.radius, true));
    }
    g
}

/// Householder least squares `A X = B`: `a` column-major `m × k` (full column rank), `b`
/// column-major `m × d`; returns `X` column-major `k × d`. `a` and `b` are overwritten.
fn least_squares(a: &mut [f64], m: usize, k: usize, b: &mut [f64], d: usize) -> Vec<f64> {
    let mut diag = vec![0.0; k];
    for j in 0..k {
        let (head, rest) = a.split_at_mut((j + 1) * m);
        let col = &mut head[j * m..];
        let norm = col[j..].iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm == 0.0 {
            continue;
        }
        let alpha = if col[j] > 0.0 { -norm } else { norm };
        col[j] -= alpha;
        let vn2: f64 = col[j..].iter().map(|v| v * v).sum();
        diag[j] = alpha;
        let v = &col[j..];
        // Plain index loops: this runs in build scripts, usually unoptimised, where iterator
        // adapters cost several times more.
        let reflect = |c: &mut [f64]| {
            let c = &mut c[j..];
            let mut s = 0.0;
            for i in 0..v.len() {
                s += v[i] * c[i];
            }
            let f = 2.0 * s / vn2;
            for i in 0..v.len() {
                c[i] -= f * v[i];
            }
        };
        for l in 0..k - j - 1 {
            reflect(&mut rest[l * m..(l + 1) * m]);
        }
        for l in 0..d {
            reflect(&mut b[l * m..(l + 1) * m]);
        }
    }
    let mut x = vec![0.0; k * d];
    for l in 0..d {
        for i in (0..k).rev() {
            let mut s = b[l * m + i];
            for jj in i + 1..k {
                s -= a[jj * m + i] * x[l * k + jj];
            }
            x[l * k + i] = if diag[i] != 0.0 { s / diag[i] } else { 0.0 };
        }
    }
    x
}

/// Inputs of the symbolic grouping: the regressor and the numeric result.
pub(super) struct Problem<'a> {
    pub ar: &'a Arena,
    pub model: &'a Model,
    pub entries: &'a [(usize, usize, ExprId)],
    /// Model parameters of the full vector.
    pub params: &'a [usize],
    /// Kept columns (base parameters), in order.
    pub kept: &'a [usize],
    /// Dependent columns (grouped into kept ones).
    pub dependent: &'a [usize],
    /// Columns without effect.
    pub unidentifiable: &'a [usize],
    /// Whether the parameters are baked (lengths folded into constants).
    pub baked: bool,
    /// The arena nodes the regressor reads ([`Arena::needed_nodes`]).
    pub needed: &'a [bool],
}

impl Problem<'_> {
    /// The coefficients of every dependent column on the kept ones for the model parameter
    /// values `values`: `X[d][k]`.
    fn solve(&self, values: &[f64], states: usize) -> Vec<Vec<f64>> {
        let n = self.model.independent_dof().max(1);
        let cols = self.params.len();
        let m = states * n;
        let (k, d) = (self.kept.len(), self.dependent.len());
        let mut a = vec![0.0; m * k];
        let mut b = vec![0.0; m * d];
        let mut rng = Rng(0x5851_f42d_4c95_7f2d);
        for s in 0..states {
            let y = regressor_at(
                self.ar,
                self.entries,
                self.model,
                values,
                self.needed,
                cols,
                &mut rng,
            );
            for r in 0..n {
                let row = s * n + r;
                for (j, &c) in self.kept.iter().enumerate() {
                    a[j * m + row] = y[r * cols + c];
                }
                for (j, &c) in self.dependent.iter().enumerate() {
                    b[j * m + row] = y[r * cols + c];
                }
            }
        }
        let x = least_squares(&mut a, m, k, &mut b, d);
        (0..d).map(|j| x[j * k..(j + 1) * k].to_vec()).collect()
    }

    /// The coefficients as expressions of the geometry (`[d][k]`) and the names of the dependent
    /// parameters whose fit failed (they keep their numbers).
    fn fit(&self) -> (Vec<Vec<Coefficient>>, Vec<usize>) {
        let base: Vec<f64> = self.model.params.iter().map(|p| p.value).collect();
        let n = self.model.independent_dof().max(1);
        // Enough rows for the kept columns with a margin (the systems are consistent).
        let states = (self.kept.len() + self.kept.len() / 4) / n + 2;
        let (k, d) = (self.kept.len(), self.dependent.len());
        let x0 = self.solve(&base, states);
        let geom = if self.baked {
            Vec::new()
        } else {
            geometry(self.model)
        };
        // 1. Dependencies on each geometric parameter.
        let tol = |row: &[f64]| 1e-8 * row.iter().fold(1.0f64, |a, v| a.max(v.abs()));
        let mut depends = vec![vec![Vec::new(); k]; d];
        for (gi, &(p, _)) in geom.iter().enumerate() {
            let mut v = base.clone();
            v[p] *= 1.3;
            let xv = self.solve(&v, states);
            for j in 0..d {
                let t = tol(&x0[j]);
                for i in 0..k {
                    if (xv[j][i] - x0[j][i]).abs() > t {
                        depends[j][i].push(gi);
                    }
                }
            }
        }
        // Candidate monomials per coefficient.
        let monomials = |deps: &[usize]| -> Vec<Vec<(usize, i32)>> {
            let poly: Vec<usize> = deps.iter().copied().filter(|&g| !geom[g].1).collect();
            let radius: Vec<usize> = deps.iter().copied().filter(|&g| geom[g].1).collect();
            let mut polys: Vec<Vec<(usize, i32)>> = vec![Vec::new()];
            for (a, &ga) in poly.iter().enumerate() {
                polys.push(vec![(geom[ga].0, 1)]);
                polys.push(vec![(geom[ga].0, 2)]);
                for &gb in &poly[a + 1..] {
                    polys.push(vec![(geom[ga].0, 1), (geom[gb].0, 1)]);
                }
            }
            let mut out = Vec::new();
            for m in polys {
                if radius.is_empty() {
                    out.push(m);
                    continue;
                }
                for &g in &radius {
                    for e in -2..=2 {
                        let mut mm = m.clone();
                        if e != 0 {
                            mm.push((geom[g].0, e));
                        }
                        mm.sort();
                        out.push(mm);
                    }
                }
            }
            out
        };
        const MAX_SAMPLES: usize = 160;
        let need = depends
            .iter()
            .flatten()
            .map(|deps| {
                if deps.is_empty() {
                    0
                } else {
                    monomials(deps).len()
                }
            })
            .max()
            .unwrap_or(0);
        let samples = if need == 0 {
            0
        } else {
            (need + 8).min(MAX_SAMPLES)
        };
        // 2. Samples on random geometries.
        let mut rng = Rng(0x2545_f491_4f6c_dd1d);
        let mut geoms = Vec::with_capacity(samples);
        let mut xs = Vec::with_capacity(samples);
        for _ in 0..samples {
            let mut v = base.clone();
            for &(p, _) in &geom {
                v[p] *= 1.0 + rng.sym(0.5);
            }
            xs.push(self.solve(&v, states));
            geoms.push(v);
        }
        let mut failed = Vec::new();
        let mut out = vec![vec![Coefficient::default(); k]; d];
        for j in 0..d {
            let t = tol(&x0[j]);
            for i in 0..k {
                let deps = &depends[j][i];
                if deps.is_empty() {
                    out[j][i] = Coefficient::number(snap(x0[j][i], t));
                    continue;
                }
                let monos = monomials(deps);
                let fitted = (monos.len() + 4 <= samples)
                    .then(|| fit_one(&monos, &geoms, &xs, j, i, t))
                    .flatten();
                match fitted {
                    Some(c) if (c.eval(&base) - x0[j][i]).abs() <= t => out[j][i] = c,
                    _ => {
                        out[j][i] = Coefficient::number(x0[j][i]);
                        failed.push(j);
                    }
                }
            }
        }
        failed.dedup();
        (out, failed)
    }

    /// Whether `Y_c = Σ coef_k Y_k` (all dependencies) holds exactly at `points` random points:
    /// per dependent column, whether it held at all of them. `None` if skipped (reason).
    fn verify(&self, coefs: &[Vec<Coefficient>], points: usize) -> Result<Vec<bool>, String> {
        if self.baked {
            return Err("baked parameters: the geometry is folded into rounded constants".into());
        }
        if !self.model.mimics.is_empty() {
            return Err("mimic joints: dependent angles are not independent circle points".into());
        }
        if self.model.is_floating() {
            return Err("floating base: the quaternion's entries are not free points".into());
        }
        let n = self.model.dof();
        let cols = self.params.len();
        let mut ok = vec![true; self.dependent.len() + self.unidentifiable.len()];
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ 0x1234_5678);
        let draw = |rng: &mut Rng| -> u64 {
            // 53 random bits from each of two draws.
            let a = (rng.next() * (1u64 << 53) as f64) as u64;
            let b = (rng.next() * (1u64 << 53) as f64) as u64;
            ((a << 11) ^ b) % modular::P
        };
        let mut done = 0;
        let mut attempts = 0;
        while done < points {
            attempts += 1;
            if attempts > 10 * points {
                return Err("no point without a division by zero".into());
            }
            let params: Vec<u64> = (0..self.model.params.len())
                .map(|_| draw(&mut rng))
                .collect();
            let Some(sin_cos) = (0..n)
                .map(|_| modular::circle_point(draw(&mut rng)))
                .collect::<Option<Vec<_>>>()
            else {
                continue;
            };
            let q: Vec<u64> = (0..n).map(|_| draw(&mut rng)).collect();
            let u: Vec<u64> = (0..n).map(|_| draw(&mut rng)).collect();
            let ud: Vec<u64> = (0..n).map(|_| draw(&mut rng)).collect();
            let Some(vals) = self.ar.eval_mod(&ModValues {
                params: &params,
                sin_cos: &sin_cos,
                q: &q,
                u: &u,
                ud: &ud,
            }) else {
                continue;
            };
            let Some(cv) = coefs
                .iter()
                .map(|row| row.iter().map(|c| c.eval_mod(&params)).collect())
                .collect::<Option<Vec<Vec<u64>>>>()
            else {
                continue;
            };
            let mut y = vec![0u64; n * cols];
            for &(r, c, e) in self.entries {
                y[r * cols + c] = modular::add(y[r * cols + c], vals[e.index()]);
            }
            for r in 0..n {
                let yr = &y[r * cols..(r + 1) * cols];
                for (j, &c) in self.dependent.iter().enumerate() {
                    let mut res = yr[c];
                    for (i, &kc) in self.kept.iter().enumerate() {
                        res = modular::add(res, modular::neg(modular::mul(cv[j][i], yr[kc])));
                    }
                    ok[j] &= res == 0;
                }
                for (j, &c) in self.unidentifiable.iter().enumerate() {
                    ok[self.dependent.len() + j] &= yr[c] == 0;
                }
            }
            done += 1;
        }
        Ok(ok)
    }
}

/// A number snapped to an integer or a fraction with denominator ≤ 12 when within `tol`.
fn snap(v: f64, tol: f64) -> f64 {
    if v.abs() <= tol {
        return 0.0;
    }
    for den in 1..=12u32 {
        let num = (v * den as f64).round();
        let r = num / den as f64;
        if (r - v).abs() <= 1e-10 * v.abs().max(1.0) {
            return r;
        }
    }
    v
}

/// Fit coefficient `[j][i]` over `monos` on the samples; `None` unless every sample is
/// reproduced to `tol`.
fn fit_one(
    monos: &[Vec<(usize, i32)>],
    geoms: &[Vec<f64>],
    xs: &[Vec<Vec<f64>>],
    j: usize,
    i: usize,
    tol: f64,
) -> Option<Coefficient> {
    let m = geoms.len();
    let k = monos.len();
    let value =
        |g: &[f64], mono: &[(usize, i32)]| mono.iter().map(|&(p, e)| g[p].powi(e)).product::<f64>();
    let mut a = vec![0.0; m * k];
    let mut scale = vec![0.0f64; k];
    for (c, mono) in monos.iter().enumerate() {
        for (s, g) in geoms.iter().enumerate() {
            a[c * m + s] = value(g, mono);
            scale[c] = scale[c].max(a[c * m + s].abs());
        }
        if scale[c] > 0.0 {
            a[c * m..(c + 1) * m]
                .iter_mut()
                .for_each(|v| *v /= scale[c]);
        }
    }
    let mut b: Vec<f64> = xs.iter().map(|x| x[j][i]).collect();
    let y = b.clone();
    let x = least_squares(&mut a, m, k, &mut b, 1);
    let mut terms = Vec::new();
    for (c, mono) in monos.iter().enumerate() {
        let v = if scale[c] > 0.0 { x[c] / scale[c] } else { 0.0 };
        // Snap relative to the monomial's size on the samples.
        let v = snap(v, tol / scale[c].max(1e-300));
        if v != 0.0 {
            terms.push((v, mono.clone()));
        }
    }
    let coef = Coefficient { terms };
    let worst = geoms
        .iter()
        .zip(&y)
        .map(|(g, yv)| (coef.eval(g) - yv).abs())
        .fold(0.0, f64::max);
    (worst <= tol * 10.0).then_some(coef)
}

/// The symbolic groups (parallel to `groups`, each kept parameter first) and the exactness
/// report of a numeric grouping.
pub(super) fn symbolic(
    pb: &Problem<'_>,
    groups: &[Vec<(usize, f64)>],
) -> (Vec<SymbolicGroup>, Exactness) {
    let (coefs, failed_fit) = pb.fit();
    let mut numeric_only: Vec<usize> = failed_fit;
    let mut ex = Exactness::default();
    match pb.verify(&coefs, 3) {
        Ok(ok) => {
            ex.points = 3;
            ex.dependencies = ok.len();
            ex.verified = ok.iter().filter(|&&b| b).count();
            numeric_only.extend(
                ok[..pb.dependent.len()]
                    .iter()
                    .enumerate()
                    .filter(|(_, b)| !**b)
                    .map(|(j, _)| j),
            );
        }
        Err(why) => ex.skipped = Some(why),
    }
    numeric_only.sort_unstable();
    numeric_only.dedup();
    ex.numeric_only = numeric_only
        .iter()
        .map(|&j| pb.model.params[pb.params[pb.dependent[j]]].name.clone())
        .collect();
    let out = groups
        .iter()
        .enumerate()
        .map(|(gi, g)| {
            let mut members = vec![(g[0].0, Coefficient::number(1.0))];
            for (j, &c) in pb.dependent.iter().enumerate() {
                let coef = if numeric_only.contains(&j) {
                    // The numeric grouping's own coefficient.
                    Coefficient::number(g.iter().find(|&&(m, _)| m == c).map_or(0.0, |&(_, v)| v))
                } else {
                    coefs[j][gi].clone()
                };
                if !coef.is_zero() {
                    members.push((c, coef));
                }
            }
            members
        })
        .collect();
    (out, ex)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn least_squares_solves_a_consistent_tall_system() {
        // A = [[1, 0], [1, 1], [1, 2]] (column-major), x = [2, -3]: b = [2, -1, -4].
        let mut a = vec![1.0, 1.0, 1.0, 0.0, 1.0, 2.0];
        let mut b = vec![2.0, -1.0, -4.0];
        let x = least_squares(&mut a, 3, 2, &mut b, 1);
        assert!(
            (x[0] - 2.0).abs() < 1e-14 && (x[1] + 3.0).abs() < 1e-14,
            "{x:?}"
        );
    }

    #[test]
    fn snapping_keeps_small_fractions_exact_and_other_numbers_as_they_are() {
        assert_eq!(snap(0.5 + 1e-13, 1e-9), 0.5);
        assert_eq!(snap(2.0 / 3.0 + 1e-13, 1e-9), 2.0 / 3.0);
        assert_eq!(snap(1e-12, 1e-9), 0.0);
        assert_eq!(snap(0.123456789, 1e-9), 0.123456789);
    }

    #[test]
    fn coefficients_evaluate_and_print_in_the_reports_style() {
        let model = kanegen_model::Model::from_toml_str(
            r#"
[model]
name = "m"
speeds = ["qd"]
[base]
type = "fixed"
frame = "0"
[gravity]
symbol = "g"
direction = [0, 0, -1]
[parameters]
g = 9.81
L1 = 0.5
m1 = 1.0
MX1 = 0.0
MY1 = 0.0
MZ1 = 0.0
XX1 = 0.1
XY1 = 0.0
XZ1 = 0.0
YY1 = 0.1
YZ1 = 0.0
ZZ1 = 0.1
[[joint]]
name = "q1"
type = "revolute"
parent = "0"
child = "1"
speed = "qd"
axis = [1, 0, 0]
rotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
translation = [0, "L1", 0]
[[body]]
frame = "1"
"#,
            "test.toml",
        )
        .expect("model loads");
        let l1 = model.param_index("L1").unwrap();
        let c = Coefficient {
            terms: vec![
                (1.0, vec![(l1, 2)]),
                (-2.0, vec![(l1, 1)]),
                (0.5, vec![(l1, -2)]),
            ],
        };
        assert_eq!(c.text(&model), "L1^2 - 2.0*L1 + 0.5/L1^2");
        let mut v = model.param_values();
        v[l1] = 2.0;
        assert_eq!(c.eval(&v), 4.0 - 4.0 + 0.125);
    }
}
