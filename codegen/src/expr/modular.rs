//! Exact evaluation of the arena modulo a prime, for identity tests.
//!
//! An identity between expressions of the arena (e.g. a base-parameter grouping, which must
//! hold for every configuration, speed, acceleration and geometry) cannot be decided by the
//! arena's simplifier, which applies no trigonometric identity. It can be tested exactly by
//! evaluating both sides in the field of integers modulo a large prime `P` at random points:
//! every constant of the arena is an f64, i.e. an exact dyadic rational, and maps exactly into
//! the field; `sin q` and `cos q` are replaced by a random point `(2t/(1+t²), (1−t²)/(1+t²))` of
//! the unit circle (the rational parametrisation, so `sin² + cos² = 1` holds exactly). A
//! difference that is not identically zero as a rational function of the leaves vanishes at a
//! random point with probability at most its degree over `P` (Schwartz–Zippel; `P ≈ 2.3·10¹⁸`),
//! and no rounding is involved: a zero at several independent points is an exact identity with
//! overwhelming probability.

use super::arena::{Arena, Atom, Node};

/// The prime `2⁶¹ − 1`.
pub const P: u64 = (1 << 61) - 1;

/// `a · b mod P`.
pub fn mul(a: u64, b: u64) -> u64 {
    ((a as u128 * b as u128) % P as u128) as u64
}

/// `a + b mod P`.
pub fn add(a: u64, b: u64) -> u64 {
    let s = a + b;
    if s >= P { s - P } else { s }
}

/// `−a mod P`.
pub fn neg(a: u64) -> u64 {
    if a == 0 { 0 } else { P - a }
}

/// `a^e mod P`.
pub fn pow(mut a: u64, mut e: u64) -> u64 {
    let mut r = 1;
    while e > 0 {
        if e & 1 == 1 {
            r = mul(r, a);
        }
        a = mul(a, a);
        e >>= 1;
    }
    r
}

/// `1/a mod P` (`None` for 0).
pub fn inv(a: u64) -> Option<u64> {
    (a != 0).then(|| pow(a, P - 2))
}

/// The exact value of a finite f64 in the field (`None` for a non-finite value).
pub fn from_f64(v: f64) -> Option<u64> {
    if !v.is_finite() {
        return None;
    }
    if v == 0.0 {
        return Some(0);
    }
    let bits = v.to_bits();
    let exp = ((bits >> 52) & 0x7ff) as i64;
    let frac = bits & ((1 << 52) - 1);
    // v = ±mant · 2^e exactly.
    let (mant, e) = if exp == 0 {
        (frac, -1074)
    } else {
        (frac | (1 << 52), exp - 1075)
    };
    let m = mant % P;
    let two_e = if e >= 0 {
        pow(2, e as u64)
    } else {
        inv(pow(2, (-e) as u64))?
    };
    let x = mul(m, two_e);
    Some(if v < 0.0 { neg(x) } else { x })
}

/// Leaf values in the field, for [`Arena::eval_mod`].
#[derive(Clone, Debug, Default)]
pub struct ModValues<'a> {
    /// Parameter values.
    pub params: &'a [u64],
    /// Per speed index: `(sin q, cos q)`, a point of the unit circle.
    pub sin_cos: &'a [(u64, u64)],
    /// Coordinates `q` (prismatic joints).
    pub q: &'a [u64],
    /// Speeds `u`.
    pub u: &'a [u64],
    /// Accelerations `u̇`.
    pub ud: &'a [u64],
}

/// The point `(2t/(1+t²), (1−t²)/(1+t²))` of the unit circle (`None` if `1 + t² = 0`).
pub fn circle_point(t: u64) -> Option<(u64, u64)> {
    let t2 = mul(t, t);
    let d = inv(add(1, t2))?;
    Some((mul(mul(2, t), d), mul(add(1, neg(t2)), d)))
}

impl Arena {
    /// Every node's value modulo [`P`]; `None` if a division by zero (mod P) occurs (draw
    /// another point) or a constant is not finite.
    pub fn eval_mod(&self, v: &ModValues<'_>) -> Option<Vec<u64>> {
        let mut out = vec![0u64; self.nodes.len()];
        for (i, n) in self.nodes.iter().enumerate() {
            out[i] = match n {
                Node::Const(c) => from_f64(c.get())?,
                Node::Atom(a) => match *a {
                    Atom::Param(p) => v.params[p as usize],
                    Atom::Speed(s) => v.u[s as usize],
                    Atom::Accel(s) => v.ud[s as usize],
                    Atom::Sin(s) => v.sin_cos[s as usize].0,
                    Atom::Cos(s) => v.sin_cos[s as usize].1,
                    Atom::Coord(s) => v.q[s as usize],
                    Atom::Var(k) => out[self.vars[k as usize].def.index()],
                },
                Node::Sum { constant, terms } => {
                    let mut acc = from_f64(constant.get())?;
                    for (t, k) in terms.iter() {
                        acc = add(acc, mul(from_f64(k.get())?, out[t.index()]));
                    }
                    acc
                }
                Node::Prod(f) => {
                    let mut acc = 1;
                    for (b, p) in f.iter() {
                        let x = out[b.index()];
                        let x = if *p < 0 { inv(x)? } else { x };
                        acc = mul(acc, pow(x, p.unsigned_abs() as u64));
                    }
                    acc
                }
            };
        }
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dyadic_constants_map_exactly() {
        let half = from_f64(0.5).unwrap();
        assert_eq!(mul(half, 2), 1);
        let x = from_f64(0.1).unwrap();
        // 0.1 as an f64 is not 1/10: 10·x ≠ 1 in the field.
        assert_ne!(mul(x, 10), 1);
        assert_eq!(add(from_f64(-3.0).unwrap(), 3), 0);
        assert_eq!(from_f64(1e-310).map(|v| v != 0), Some(true));
    }

    #[test]
    fn circle_points_satisfy_the_pythagorean_identity() {
        for t in [2u64, 12345, P - 7] {
            let (s, c) = circle_point(t).unwrap();
            assert_eq!(add(mul(s, s), mul(c, c)), 1);
        }
    }
}
