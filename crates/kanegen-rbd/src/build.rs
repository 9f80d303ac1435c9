//! Construction of an [`Rbd`]: parameter evaluation, merging of fixed joints, and the change of
//! every moving frame to one whose joint axis is `+z`.

use kanegen_model::{Base, JointKind, Model, Mount};
use nalgebra::{Matrix3, Vector3};

use crate::rot::RotKind;
use crate::scalar::{M3, S3, Scalar, V3};
use crate::{AncEntry, Axis, LinkData, ROOT, Rbd, RbdError, RootData, Wheels};

/// Classifies a unit axis.
pub(crate) fn classify(e: [f64; 3]) -> Axis {
    match e {
        [1.0, 0.0, 0.0] => Axis::PosX,
        [-1.0, 0.0, 0.0] => Axis::NegX,
        [0.0, 1.0, 0.0] => Axis::PosY,
        [0.0, -1.0, 0.0] => Axis::NegY,
        [0.0, 0.0, 1.0] => Axis::PosZ,
        [0.0, 0.0, -1.0] => Axis::NegZ,
        _ => Axis::General,
    }
}

/// `C` (columns: the new frame's axes in the old frame), a proper rotation with `C ẑ = e`.
pub(crate) fn canonical_frame(axis: Axis, e: [f64; 3]) -> Matrix3<f64> {
    let x = Vector3::x();
    let y = Vector3::y();
    let zz = Vector3::z();
    let cols = match axis {
        Axis::PosX => [y, zz, x],
        Axis::NegX => [zz, y, -x],
        Axis::PosY => [zz, x, y],
        Axis::NegY => [x, zz, -y],
        Axis::PosZ => [x, y, zz],
        Axis::NegZ => [y, x, -zz],
        Axis::General => {
            let e = Vector3::from(e).normalize();
            // The coordinate axis least aligned with e, orthogonalised.
            let k = (0..3)
                .min_by(|&a, &b| e[a].abs().total_cmp(&e[b].abs()))
                .unwrap_or(0);
            let mut helper = Vector3::zeros();
            helper[k] = 1.0;
            let c0 = (helper - e * e.dot(&helper)).normalize();
            let c1 = e.cross(&c0);
            [c0, c1, e]
        }
    };
    Matrix3::from_columns(&cols)
}

/// `(idx, sign)` with `(A x)[a] = sign[a] · x[idx[a]]`, if `A` is a signed permutation.
fn signed_perm(a: &Matrix3<f64>) -> Option<([usize; 3], [f64; 3])> {
    let mut idx = [0; 3];
    let mut sign = [0.0; 3];
    for r in 0..3 {
        let nz: Vec<usize> = (0..3).filter(|&c| a[(r, c)] != 0.0).collect();
        if nz.len() != 1 || a[(r, nz[0])].abs() != 1.0 {
            return None;
        }
        idx[r] = nz[0];
        sign[r] = a[(r, nz[0])];
    }
    Some((idx, sign))
}

/// Inertial parameters `(m, h, J about the origin)` of a (merged) body, in some frame.
#[derive(Clone)]
struct Inertial<T: Scalar> {
    m: T,
    h: Vector3<T>,
    j: Matrix3<T>,
}

impl<T: Scalar> Inertial<T> {
    fn zero() -> Self {
        Self {
            m: T::zero(),
            h: Vector3::zeros(),
            j: Matrix3::zeros(),
        }
    }

    /// The same body expressed in a frame where `x_new = a x_old + t`.
    fn transformed(&self, a: &Matrix3<T>, t: &Vector3<T>) -> Self {
        let h = a * self.h;
        let j = a * self.j * a.transpose();
        let two: T = nalgebra::convert(2.0);
        let shift = Matrix3::identity() * (self.m * t.norm_squared() + two * t.dot(&h))
            - t * t.transpose() * self.m
            - t * h.transpose()
            - h * t.transpose();
        Self {
            m: self.m,
            h: h + t * self.m,
            j: j + shift,
        }
    }

    fn add(&mut self, o: &Self) {
        self.m += o.m;
        self.h += o.h;
        self.j += o.j;
    }
}

/// A moving link under construction.
struct Proto<T: Scalar> {
    parent: usize,
    speed: usize,
    prismatic: bool,
    axis: Axis,
    a: Matrix3<f64>,
    p: Vector3<T>,
    body: Inertial<T>,
}

fn v3<T: Scalar>(v: &Vector3<T>) -> V3<T> {
    [v[0], v[1], v[2]]
}

fn m3<T: Scalar>(a: &Matrix3<f64>) -> M3<T> {
    let c = |k: usize| -> V3<T> {
        [
            nalgebra::convert(a[(0, k)]),
            nalgebra::convert(a[(1, k)]),
            nalgebra::convert(a[(2, k)]),
        ]
    };
    [c(0), c(1), c(2)]
}

fn s3<T: Scalar>(j: &Matrix3<T>) -> S3<T> {
    [
        j[(0, 0)],
        j[(0, 1)],
        j[(0, 2)],
        j[(1, 1)],
        j[(1, 2)],
        j[(2, 2)],
    ]
}

/// Which speeds some joint (or the wheeled base) drives; each exactly once.
struct Driven(Vec<bool>);

impl Driven {
    fn drive(&mut self, s: usize, who: &str) -> Result<(), RbdError> {
        if s >= self.0.len() || self.0[s] {
            return Err(RbdError::BadSpeeds {
                detail: format!("{who}: speed index {s} is out of range or driven twice"),
            });
        }
        self.0[s] = true;
        Ok(())
    }

    fn check_all(&self, model: &Model) -> Result<(), RbdError> {
        match self.0.iter().position(|d| !d) {
            Some(s) => Err(RbdError::BadSpeeds {
                detail: format!("speed `{}` is driven by no joint", model.speeds[s].name),
            }),
            None => Ok(()),
        }
    }
}

fn check_sizes<const N: usize>(model: &Model, params: usize) -> Result<(), RbdError> {
    if model.dof() != N {
        return Err(RbdError::DofMismatch {
            model: model.name.clone(),
            model_dof: model.dof(),
            requested: N,
        });
    }
    if params != model.params.len() {
        return Err(RbdError::ParamCount {
            expected: model.params.len(),
            given: params,
        });
    }
    Ok(())
}

/// The moving links (fixed joints merged into the moving link or root they hang from, every
/// moving frame turned so that its axis is `+z`) and the bodies rigidly attached to the root.
fn moving_links<T: Scalar>(
    model: &Model,
    params: &[T],
    driven: &mut Driven,
) -> Result<(Vec<Proto<T>>, Inertial<T>), RbdError> {
    let cv = |x: f64| -> T { nalgebra::convert(x) };
    let param = |id: usize| -> T { params[id] };
    // For each model link: the moving link (or ROOT) it is rigidly attached to, and the
    // transform x_that = A x_this + t into that link's +z-axis frame.
    let mut eff: Vec<(usize, Matrix3<f64>, Vector3<T>)> = Vec::with_capacity(model.links.len());
    let mut protos: Vec<Proto<T>> = Vec::new();
    let mut root_body = Inertial::<T>::zero();
    for (k, link) in model.links.iter().enumerate() {
        match (k, &link.mount) {
            (0, None) => eff.push((ROOT, Matrix3::identity(), Vector3::zeros())),
            (_, Some(Mount { parent: pi, joint })) if *pi < k => {
                let (r_par, a_par, t_par) = eff[*pi];
                let a0 = Matrix3::from_fn(|r, c| joint.rotation[r][c]);
                let p0 = Vector3::from_fn(|r, _| {
                    let s = joint.translation[r];
                    match s.symbol {
                        Some(id) => cv(s.coef) * param(id),
                        None => cv(s.coef),
                    }
                });
                let p_eff = a_par.map(cv) * p0 + t_par;
                match joint.kind {
                    JointKind::Fixed => eff.push((r_par, a_par * a0, p_eff)),
                    JointKind::Revolute { speed: s } | JointKind::Prismatic { speed: s } => {
                        driven.drive(s, &format!("joint `{}`", joint.name))?;
                        let axis = classify(joint.axis);
                        let c = canonical_frame(axis, joint.axis);
                        protos.push(Proto {
                            parent: r_par,
                            speed: s,
                            prismatic: matches!(joint.kind, JointKind::Prismatic { .. }),
                            axis,
                            a: a_par * a0 * c,
                            p: p_eff,
                            body: Inertial::zero(),
                        });
                        eff.push((protos.len() - 1, c.transpose(), Vector3::zeros()));
                    }
                }
            }
            _ => {
                return Err(RbdError::BadTree {
                    link: link.name.clone(),
                    detail: "links must be in topological order with links[0] the only root".into(),
                });
            }
        }
        if let Some(b) = &link.body {
            let body = Inertial {
                m: param(b.mass),
                h: Vector3::from_fn(|r, _| param(b.first_moment[r])),
                j: {
                    let [xx, xy, xz, yy, yz, zz] = b.inertia.map(param);
                    Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz)
                },
            };
            let (r, a, t) = &eff[k];
            let moved = body.transformed(&a.map(cv), t);
            if *r == ROOT {
                root_body.add(&moved);
            } else {
                protos[*r].body.add(&moved);
            }
        }
    }
    Ok((protos, root_body))
}

/// The constant wheel terms of a wheeled base.
fn wheels<T: Scalar>(
    model: &Model,
    params: &[T],
    driven: &mut Driven,
) -> Result<Option<Wheels<T>>, RbdError> {
    let Base::Wheeled(w) = &model.base else {
        return Ok(None);
    };
    driven.drive(w.x_speed, "the wheeled base's x speed")?;
    driven.drive(w.psi_speed, "the wheeled base's psi speed")?;
    let param = |id: usize| -> T { params[id] };
    let (r, l, mw, yy, zz) = (
        param(w.radius),
        param(w.track),
        param(w.wheel_mass),
        param(w.wheel_axle_inertia),
        param(w.wheel_diametral_inertia),
    );
    let two: T = nalgebra::convert(2.0);
    Ok(Some(Wheels {
        x: w.x_speed,
        psi: w.psi_speed,
        m_xx: two * mw + two * yy / (r * r),
        m_psipsi: mw * l * l / two + yy * l * l / (two * r * r) + two * zz,
        mass: two * mw,
    }))
}

/// Subtree masses of the moving links, and the root's.
fn subtree_masses<T: Scalar>(protos: &[Proto<T>], root_body: &Inertial<T>) -> (Vec<T>, T) {
    let mut mc: Vec<T> = protos.iter().map(|p| p.body.m).collect();
    let mut mc_root = root_body.m;
    for j in (0..protos.len()).rev() {
        match protos[j].parent {
            ROOT => mc_root += mc[j],
            p => {
                let v = mc[j];
                mc[p] += v;
            }
        }
    }
    (mc, mc_root)
}

/// The hot-path data of a moving link: its rotation kind (signed permutations are applied
/// without forming the matrix), offset, body and subtree mass.
fn link_data<T: Scalar>(p: &Proto<T>, j: usize, mc: T) -> LinkData<T> {
    let cv = |x: f64| -> T { nalgebra::convert(x) };
    let z = T::zero();
    let (kind, g, sym_sign) = match signed_perm(&p.a) {
        Some((idx, sign)) => {
            // Row a of R = A' Rot_z is sign[a] times row idx[a] of Rot_z.
            let mut rows = [0; 3];
            let mut g = [z; 3];
            for a in 0..3 {
                rows[idx[a]] = a;
                g[idx[a]] = cv(sign[a]);
            }
            let mut sym_sign = [z; 6];
            for (k, (a, b)) in [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]
                .into_iter()
                .enumerate()
            {
                sym_sign[k] = cv(sign[a] * sign[b]);
            }
            (RotKind::from_rows(rows), g, sym_sign)
        }
        None => (RotKind::General, [cv(1.0); 3], [cv(1.0); 6]),
    };
    let pv = v3(&p.p);
    LinkData {
        parent: p.parent,
        chain: p.parent != ROOT && p.parent + 1 == j,
        speed: p.speed,
        prismatic: p.prismatic,
        a: m3(&p.a),
        kind,
        g,
        sym_sign,
        p: pv,
        offset: p.prismatic || pv.iter().any(|x| *x != z),
        m: p.body.m,
        h: v3(&p.body.h),
        j: s3(&p.body.j),
        mc,
        mc_p: v3(&(p.p * mc)),
        half_mc_p: v3(&(p.p * (mc * cv(0.5)))),
    }
}

/// A link with every field zero (the unused tail of the fixed-size link array).
fn blank_link<T: Scalar>() -> LinkData<T> {
    let z = T::zero();
    LinkData {
        parent: ROOT,
        chain: false,
        speed: 0,
        prismatic: false,
        a: [[z; 3]; 3],
        kind: RotKind::General,
        g: [z; 3],
        sym_sign: [z; 6],
        p: [z; 3],
        offset: false,
        m: z,
        h: [z; 3],
        j: [z; 6],
        mc: z,
        mc_p: [z; 3],
        half_mc_p: [z; 3],
    }
}

/// Ancestor lists for the CRBA (nearest first), plus the base speeds of a wheeled base.
fn ancestor_lists<const N: usize, T: Scalar>(
    links: &[LinkData<T>; N],
    nl: usize,
    wheels: Option<&Wheels<T>>,
) -> ([[AncEntry; N]; N], [usize; N]) {
    let mut anc = [[AncEntry::default(); N]; N];
    let mut anc_len = [0; N];
    let entry = |k: usize, sk: usize, sj: usize| AncEntry {
        k,
        upper: sk + sj * N,
        lower: sj + sk * N,
    };
    for j in 0..nl {
        let sj = links[j].speed;
        let mut list = Vec::new();
        let mut k = links[j].parent;
        while k != ROOT {
            list.push(entry(k, links[k].speed, sj));
            k = links[k].parent;
        }
        if let Some(w) = wheels {
            list.push(entry(nl, w.x, sj));
            list.push(entry(nl + 1, w.psi, sj));
        }
        anc_len[j] = list.len();
        anc[j][..list.len()].copy_from_slice(&list);
    }
    (anc, anc_len)
}

pub(crate) fn build<const N: usize, T: Scalar>(
    model: &Model,
    params: &[T],
) -> Result<Rbd<N, T>, RbdError> {
    check_sizes::<N>(model, params.len())?;
    let mut driven = Driven(vec![false; N]);
    let (protos, root_body) = moving_links(model, params, &mut driven)?;
    let wheels = wheels(model, params, &mut driven)?;
    driven.check_all(model)?;
    let nl = protos.len();
    let (mc, mc_root) = subtree_masses(&protos, &root_body);
    let mut links = [blank_link(); N];
    let mut axes = [Axis::PosZ; N];
    for (j, p) in protos.iter().enumerate() {
        links[j] = link_data(p, j, mc[j]);
        axes[j] = p.axis;
    }
    let (anc, anc_len) = ancestor_lists(&links, nl, wheels.as_ref());
    let cv = |x: f64| -> T { nalgebra::convert(x) };
    let g = model.gravity.direction.map(cv);
    let gm = params[model.gravity.symbol];
    Ok(Rbd {
        nl,
        links,
        root: RootData {
            m: root_body.m,
            h: v3(&root_body.h),
            j: s3(&root_body.j),
            mc: mc_root,
            grav: [-(gm * g[0]), -(gm * g[1]), -(gm * g[2])],
            wheels,
        },
        axes,
        anc,
        anc_len,
    })
}
