//! WGSL text of the lowered form: literals of the kernel's float type, leaves read from the
//! per-invocation state, expressions, statement lists, and the sine/cosine routine every kernel
//! calls once per joint angle.

use std::fmt::Write as _;

use crate::lower::{LExpr, Leaf, Program, sum_order};

/// The float type of one copy of the kernels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Float {
    /// `f32`: every adapter.
    F32,
    /// `f64`: adapters with `SHADER_F64`.
    F64,
}

impl Float {
    /// The WGSL type name.
    pub(super) fn ty(self) -> &'static str {
        match self {
            Float::F32 => "f32",
            Float::F64 => "f64",
        }
    }

    /// A literal of this type (`0.5f`, `0.5lf`); `None` when `v` is not a finite number of
    /// the type. Negative values are parenthesised.
    pub(super) fn lit(self, v: f64) -> Option<String> {
        let (text, suffix) = match self {
            Float::F32 => {
                let x = v as f32;
                if !x.is_finite() {
                    return None;
                }
                (format!("{x:?}"), "f")
            }
            Float::F64 => {
                if !v.is_finite() {
                    return None;
                }
                (format!("{v:?}"), "lf")
            }
        };
        // `{:?}` prints `1e-5` and `1.0`; both take the suffix as they are.
        Some(if text.starts_with('-') {
            format!("({text}{suffix})")
        } else {
            format!("{text}{suffix}")
        })
    }
}

/// A dependent (mimic) speed: `q[s] = a·q[master] + b`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Mimic {
    /// The dependent speed.
    pub(super) speed: usize,
    /// Its independent master.
    pub(super) master: usize,
    /// `a`.
    pub(super) multiplier: f64,
    /// `b`.
    pub(super) offset: f64,
}

/// Prints lowered expressions as WGSL, reading the state from the function argument `st`
/// (`st.q`, `st.u`, `st.a`, `st.s`, `st.c`), the parameters from `params` and the precomputed
/// values from `pre`.
pub(super) struct Printer<'a> {
    /// The float type.
    pub(super) float: Float,
    /// The program's statement names (`k12`, `t3`).
    pub(super) names: Vec<&'a str>,
    /// The dependent speeds.
    pub(super) mimics: &'a [Mimic],
}

/// A constant that is not a finite number of the kernel's type.
#[derive(Debug)]
pub(super) struct BadConstant(pub(super) f64);

impl Printer<'_> {
    fn lit(&self, v: f64) -> Result<String, BadConstant> {
        self.float.lit(v).ok_or(BadConstant(v))
    }

    /// `field[s]`, or for a dependent speed the master's value scaled (and offset, for `q`).
    fn state(&self, field: &str, s: usize, offset: bool) -> Result<String, BadConstant> {
        match self.mimics.iter().find(|m| m.speed == s) {
            None => Ok(format!("st.{field}[{s}]")),
            Some(m) => {
                let mut t = format!("({} * st.{field}[{}]", self.lit(m.multiplier)?, m.master);
                if offset && m.offset != 0.0 {
                    write!(t, " + {}", self.lit(m.offset)?).expect("string");
                }
                t.push(')');
                Ok(t)
            }
        }
    }

    fn leaf(&self, l: Leaf, out: &mut String) -> Result<(), BadConstant> {
        let text = match l {
            Leaf::Const(v) => self.lit(v)?,
            Leaf::Param(p) => format!("params[{p}]"),
            Leaf::Pre(k) => format!("pre[{k}]"),
            Leaf::Speed(s) => self.state("u", s, false)?,
            Leaf::Accel(s) => self.state("a", s, false)?,
            Leaf::Coord(s) => self.state("q", s, true)?,
            // Sines and cosines of every angle, dependent ones included, are in the state.
            Leaf::Sin(s) => format!("st.s[{s}]"),
            Leaf::Cos(s) => format!("st.c[{s}]"),
            Leaf::Local(i) => self.names[i].to_owned(),
        };
        out.push_str(&text);
        Ok(())
    }

    /// Appends the WGSL text of `e`, parenthesised unless it is a leaf.
    pub(super) fn expr(&self, e: &LExpr, out: &mut String) -> Result<(), BadConstant> {
        match e {
            LExpr::Leaf(l) => self.leaf(*l, out),
            LExpr::Sum { constant, terms } => {
                out.push('(');
                for (j, i) in sum_order(terms).enumerate() {
                    let (k, t) = &terms[i];
                    let (sign, mag) = if *k < 0.0 { ('-', -k) } else { ('+', *k) };
                    match (j, sign) {
                        (0, '-') => out.push('-'),
                        (0, _) => {}
                        (_, s) => write!(out, " {s} ").expect("string"),
                    }
                    if mag != 1.0 {
                        out.push_str(&self.lit(mag)?);
                        out.push_str(" * ");
                    }
                    self.expr(t, out)?;
                }
                if *constant != 0.0 {
                    let sign = if *constant < 0.0 { '-' } else { '+' };
                    write!(out, " {sign} {}", self.lit(constant.abs())?).expect("string");
                }
                out.push(')');
                Ok(())
            }
            LExpr::Prod(factors) => {
                let side = |positive: bool, out: &mut String| -> Result<usize, BadConstant> {
                    let mut n = 0;
                    for (b, p) in factors {
                        if (*p > 0) != positive {
                            continue;
                        }
                        for _ in 0..p.unsigned_abs() {
                            if n > 0 {
                                out.push_str(" * ");
                            }
                            self.expr(b, out)?;
                            n += 1;
                        }
                    }
                    Ok(n)
                };
                out.push('(');
                if side(true, out)? == 0 {
                    out.push_str(&self.lit(1.0)?);
                }
                let mut den = String::new();
                if side(false, &mut den)? > 0 {
                    write!(out, " / ({den})").expect("string");
                }
                out.push(')');
                Ok(())
            }
        }
    }
}

/// The statements of `p` as `let NAME: T = EXPR;` lines (indented by `indent`), then
/// `return array<T, E>(…)` of its outputs in their order (one zero for a program without
/// outputs).
pub(super) fn body(
    p: &Program,
    float: Float,
    mimics: &[Mimic],
    indent: &str,
    out: &mut String,
) -> Result<(), BadConstant> {
    let printer = Printer {
        float,
        names: p.stmts.iter().map(|s| s.name.as_str()).collect(),
        mimics,
    };
    let ty = float.ty();
    for s in &p.stmts {
        write!(out, "{indent}let {}: {ty} = ", s.name).expect("string");
        printer.expr(&s.expr, out)?;
        out.push_str(";\n");
    }
    let n = p.outputs.len().max(1);
    write!(out, "{indent}return array<{ty}, {n}>(").expect("string");
    if p.outputs.is_empty() {
        out.push_str(&printer.lit(0.0)?);
    }
    for (i, (_, _, e)) in p.outputs.iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        printer.expr(e, out)?;
    }
    out.push_str(");\n");
    Ok(())
}

/// `fn sin_cos(x: T) -> vec2<T>`: the runtime's own routine (`kanegen_runtime::trig`) in
/// WGSL: Cody–Waite reduction by π/2 and minimax polynomials on [−π/4, π/4], the quadrant
/// applied by `select`. No `sin`/`cos` built-in: for `f64` those lower to SPIR-V instructions
/// defined for 16- and 32-bit floats only, which some drivers evaluate to garbage without an
/// error. `f32`: Cephes' kernels and a three-part π/2 (the `f32` module's routine); `f64`:
/// fdlibm's kernels and a three-part π/2 (exact products for |x| < 2¹⁹·π/2).
pub(super) fn sin_cos_fn(float: Float) -> String {
    match float {
        Float::F32 => "fn sin_cos(x: f32) -> vec2<f32> {
    let n = round(x * 0.63661975f);
    let r = ((x - n * 1.5703125f) - n * 4.8375129699707031e-4f) - n * 7.5497899548918822e-8f;
    let z = r * r;
    let s = ((-1.9515295891e-4f * z + 8.3321608736e-3f) * z - 1.6666654611e-1f) * z * r + r;
    let c = ((2.443315711809948e-5f * z - 1.388731625493765e-3f) * z + 4.166664568298827e-2f) * z * z - 0.5f * z + 1.0f;
    return quadrant_f32(s, c, i32(n));
}

fn quadrant_f32(s: f32, c: f32, n: i32) -> vec2<f32> {
    let k = n & 3;
    let odd = (k & 1) == 1;
    let sw = select(vec2<f32>(s, c), vec2<f32>(c, s), odd);
    let sin_sign = select(1.0f, -1.0f, k >= 2);
    let cos_sign = select(1.0f, -1.0f, k == 1 || k == 2);
    return vec2<f32>(sw.x * sin_sign, sw.y * cos_sign);
}
"
        .to_owned(),
        Float::F64 => "fn sin_cos(x: f64) -> vec2<f64> {
    let n = round(x * 0.6366197723675814lf);
    let r1 = x - n * 1.5707963267341256lf;
    let w = n * 6.077100506303966e-11lf;
    let r2 = r1 - w;
    let w2 = n * 2.0222662487959506e-21lf - ((r1 - r2) - w);
    let r = r2 - w2;
    let z = r * r;
    let ps = -1.6666666666666632e-1lf + z * (8.33333333332249e-3lf + z * (-1.984126982985795e-4lf + z * (2.7557313707070068e-6lf + z * (-2.5050760253406863e-8lf + z * 1.58969099521155e-10lf))));
    let s = r + r * z * ps;
    let pc = 4.16666666666666e-2lf + z * (-1.388888888887411e-3lf + z * (2.480158728947673e-5lf + z * (-2.7557314351390663e-7lf + z * (2.087572321298175e-9lf + z * (-1.1359647557788195e-11lf)))));
    let hz = 0.5lf * z;
    let omh = 1.0lf - hz;
    let c = omh + (z * z * pc + ((1.0lf - omh) - hz));
    let k = i32(n - 4.0lf * floor(n * 0.25lf));
    let odd = (k & 1) == 1;
    let sw = select(vec2<f64>(s, c), vec2<f64>(c, s), odd);
    let sin_sign = select(1.0lf, -1.0lf, k >= 2);
    let cos_sign = select(1.0lf, -1.0lf, k == 1 || k == 2);
    return vec2<f64>(sw.x * sin_sign, sw.y * cos_sign);
}
"
        .to_owned(),
    }
}
