//! The two-wheeled base: which links it replaces (the joint above the body link, the wheel
//! subtrees), the wheel geometry and constants, and its frames in the IR.

use nalgebra::{Matrix3, Vector3};

use super::inertia::{Inertial, merge};
use super::options::{WheeledBaseSpec, bad_option};
use super::resolved::{Ir, Resolved};
use super::transform::{Notes, Tf, clean, finite3, numbers, rows};
use crate::error::ModelErrorKind as K;
use crate::ident::sanitize_identifier;
use crate::ir::*;

/// The wheeled base, resolved against the tree.
pub(super) struct WheelGeometry {
    /// `0A1(0)`: the heading frame's axes (rows) in the body frame.
    a01: Matrix3<f64>,
    /// `0P1`: the body origin in the heading frame.
    p01: Vector3<f64>,
    /// Pitch axis in the body frame.
    axis: Vector3<f64>,
    /// Track `L`.
    track: f64,
    /// Mass of one wheel `mw`.
    mass: f64,
    /// `YYw`.
    axle: f64,
    /// `ZZw`.
    diametral: f64,
}

/// One wheel as found in the URDF, in the body frame.
struct Wheel {
    /// The wheel joint's origin.
    centre: Vector3<f64>,
    /// The wheel joint's unit axis.
    axis: Vector3<f64>,
    /// Mass, moment about the axle and mean diametral moment of the wheel and the links fixed
    /// to it (zeros if massless).
    consts: (f64, f64, f64),
}

/// Measures the wheel of joint `k` (declared as `option`): its centre and axis in the body frame,
/// its mass and moments; notes a wheel that is not axisymmetric or whose centre of mass is off
/// the axle.
fn measure_wheel(k: usize, option: &str, r: &Resolved<'_>, notes: &mut Notes) -> Result<Wheel, K> {
    let (tree, cl) = (&r.tree, &r.clusters);
    let body_name = &tree.link(cl.body).name;
    let j = tree.joint(k);
    let p = tree.parent_of(k);
    if cl.cluster_top[p] == usize::MAX || cl.rep(p) != cl.body {
        return Err(bad_option(
            option,
            format!(
                "`{}` hangs from `{}`, which is neither the body link `{body_name}` nor fixed to it",
                j.name, j.parent.link
            ),
        ));
    }
    let t = cl.in_rep(p).then(&r.origin[k].expect("origin"));
    let a = Vector3::from(j.axis.xyz.0);
    if !(finite3(j.axis.xyz.0) && a.norm() > 0.0) {
        return Err(bad_option(
            option,
            format!("`{}` has no usable <axis> ({:?})", j.name, j.axis.xyz.0),
        ));
    }
    let a = a.normalize();
    // The wheel and the links fixed to it, merged in the wheel link's frame.
    let c = tree.child_of(k);
    let items: Vec<(Tf, Inertial)> = tree
        .preorder(c, &|kk| !r.dropped[tree.child_of(kk)])
        .into_iter()
        .filter_map(|l| r.inertial[l].map(|i| (cl.in_top[l], i)))
        .collect();
    let (m, ms, jo) = merge(&items);
    // A massless wheel keeps its rotational inertia (UrdfOptions::zero_mass_inertia).
    let (com, ig) = if m > 0.0 {
        let com = ms / m;
        (
            com,
            jo - (Matrix3::identity() * com.norm_squared() - com * com.transpose()) * m,
        )
    } else {
        (Vector3::zeros(), jo)
    };
    let consts = {
        let yy = (a.transpose() * ig * a)[(0, 0)];
        let zz = (ig.trace() - yy) / 2.0;
        // The two diametral principal moments (eigenvalues of I_G restricted to the plane ⟂ a).
        let b = if a.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let b = (b - a * a.dot(&b)).normalize();
        let cc = a.cross(&b);
        let (bb, bc, ccc) = (
            (b.transpose() * ig * b)[(0, 0)],
            (b.transpose() * ig * cc)[(0, 0)],
            (cc.transpose() * ig * cc)[(0, 0)],
        );
        let half = ((bb - ccc) * (bb - ccc) / 4.0 + bc * bc).sqrt();
        let (d1, d2) = ((bb + ccc) / 2.0 - half, (bb + ccc) / 2.0 + half);
        if d2 - d1 > 1e-3 * d2.abs() {
            notes.push(format!(
                "wheel `{}`: not axisymmetric about its axle (diametral moments {d1:.6} and {d2:.6} kg·m²); their mean {zz:.6} is used as ZZw unless overridden",
                j.child.link
            ));
        }
        let off = (com - a * com.dot(&a)).norm();
        if off > 1e-6 {
            notes.push(format!(
                "wheel `{}`: centre of mass {off:.3e} m off the axle (ignored by the wheel terms)",
                j.child.link
            ));
        }
        (m, yy, zz)
    };
    Ok(Wheel {
        centre: t.p,
        axis: t.r * a,
        consts,
    })
}

/// Resolves the wheeled base declaration: heading frame, pitch axis and wheel constants.
pub(super) fn wheel_geometry(
    w: &WheeledBaseSpec,
    r: &Resolved<'_>,
    notes: &mut Notes,
) -> Result<WheelGeometry, K> {
    let body_name = &r.tree.link(r.clusters.body).name;
    let mut wheels = Vec::new();
    for (&k, option) in r
        .cut
        .wheel_joints
        .iter()
        .zip(["base.left_wheel_joint", "base.right_wheel_joint"])
    {
        wheels.push(measure_wheel(k, option, r, notes)?);
    }
    let (cl_, cr) = (wheels[0].centre, wheels[1].centre);
    let (al, ar) = (wheels[0].axis, wheels[1].axis);
    let consts = [wheels[0].consts, wheels[1].consts];
    if al.cross(&ar).norm() > 1e-6 {
        return Err(bad_option(
            "base.right_wheel_joint",
            format!(
                "the wheel axes are not parallel: left {:?}, right {:?} in the body frame `{body_name}`",
                al.as_slice(),
                ar.as_slice()
            ),
        ));
    }
    let d = cl_ - cr;
    if d.norm() < 1e-9 {
        return Err(bad_option(
            "base.right_wheel_joint",
            "the two wheel joint origins coincide; the track is the distance between them".into(),
        ));
    }
    let e1 = al;
    let lateral = (d - e1 * d.dot(&e1)).norm();
    if lateral > 1e-6 {
        return Err(bad_option(
            "base.right_wheel_joint",
            format!(
                "the wheel centres are not on one axle: the line between them is {lateral:.3e} m off the wheel axis"
            ),
        ));
    }
    let y0 = if d.dot(&e1) > 0.0 { e1 } else { -e1 };
    let up = Vector3::from(w.up);
    if !(finite3(w.up) && up.norm() > 0.0) {
        return Err(bad_option(
            "base.up",
            format!("{:?} is not a direction", w.up),
        ));
    }
    let z0 = up.normalize();
    if z0.dot(&y0).abs() > 1e-9 {
        return Err(bad_option(
            "base.up",
            format!(
                "{:?} is not perpendicular to the wheel axis {:?} (body frame `{body_name}`); give the body axis that points up at zero pitch",
                w.up,
                e1.as_slice()
            ),
        ));
    }
    let x0 = y0.cross(&z0);
    let a01 = Matrix3::from_rows(&[x0.transpose(), y0.transpose(), z0.transpose()]).map(clean);
    let mid = (cl_ + cr) / 2.0;
    let p01 = -(a01 * mid);
    let geometric = d.norm();
    let mean = |i: usize| {
        let (l, r) = (consts[0], consts[1]);
        let v = [l.0, l.1, l.2];
        let u = [r.0, r.1, r.2];
        (v[i] + u[i]) / 2.0
    };
    if (consts[0].0 - consts[1].0).abs() > 1e-9 * consts[0].0.max(consts[1].0) {
        notes.push(format!(
            "wheel masses differ ({} and {} kg); their mean is used",
            consts[0].0, consts[1].0
        ));
    }
    let g = WheelGeometry {
        a01,
        p01,
        axis: e1.map(clean),
        track: w.track.unwrap_or(geometric),
        mass: w.wheel_mass.unwrap_or(mean(0)),
        axle: w.wheel_axle_inertia.unwrap_or(mean(1)),
        diametral: w.wheel_diametral_inertia.unwrap_or(mean(2)),
    };
    let src = |given: bool| if given { "given" } else { "from the URDF" };
    notes.push(format!(
        "wheeled base: body `{body_name}`, heading frame 0 at the wheel centres' midpoint {:?} of `{body_name}`, pitch axis {:?}; R = {} (given), L = {} ({}; wheel joint origins {geometric} apart), mw = {} ({}), YYw = {} ({}), ZZw = {} ({})",
        mid.map(clean).as_slice(),
        g.axis.as_slice(),
        w.radius,
        g.track,
        src(w.track.is_some()),
        g.mass,
        src(w.wheel_mass.is_some()),
        g.axle,
        src(w.wheel_axle_inertia.is_some()),
        g.diametral,
        src(w.wheel_diametral_inertia.is_some()),
    ));
    Ok(g)
}

/// Adds the wheeled base to the IR: its parameters `R`, `L`, `mw`, `YYw`, `ZZw`, the speeds `xd`,
/// `psid` and the pitch speed, the heading frame `0` and the body frame on the pitch joint.
pub(super) fn add_base(
    ir: &mut Ir,
    w: &WheeledBaseSpec,
    wg: &WheelGeometry,
    r: &Resolved<'_>,
) -> Result<Base, K> {
    let radius = ir.param("R".into(), w.radius, ParamKind::Wheel);
    let track = ir.param("L".into(), wg.track, ParamKind::Wheel);
    let wheel_mass = ir.param("mw".into(), wg.mass, ParamKind::Wheel);
    let axle = ir.param("YYw".into(), wg.axle, ParamKind::Wheel);
    let diam = ir.param("ZZw".into(), wg.diametral, ParamKind::Wheel);
    if r.tree.index.contains_key("0") {
        return Err(K::Duplicate {
            what: "frame (the wheeled base's heading frame is `0`)",
            name: "0".into(),
        });
    }
    ir.speeds.push(Speed {
        name: "xd".into(),
        coordinate: "x".into(),
    });
    ir.speeds.push(Speed {
        name: "psid".into(),
        coordinate: "psi".into(),
    });
    ir.speeds.push(Speed {
        name: sanitize_identifier(&format!("qd_{}", w.pitch_name)),
        coordinate: sanitize_identifier(&format!("q_{}", w.pitch_name)),
    });
    ir.links.push(Link {
        name: "0".into(),
        mount: None,
        body: None,
    });
    let body = r.cut.body;
    ir.links.push(Link {
        name: r.tree.link(body).name.clone(),
        mount: Some(Mount {
            parent: 0,
            joint: Joint {
                name: w.pitch_name.clone(),
                kind: JointKind::Revolute { speed: 2 },
                axis: [wg.axis.x, wg.axis.y, wg.axis.z],
                rotation: rows(&wg.a01),
                translation: numbers(wg.p01),
            },
        }),
        body: None,
    });
    ir.ir_index.insert(body, 1);
    Ok(Base::Wheeled(WheeledBase {
        x_speed: 0,
        psi_speed: 1,
        radius,
        track,
        wheel_mass,
        wheel_axle_inertia: axle,
        wheel_diametral_inertia: diam,
    }))
}
