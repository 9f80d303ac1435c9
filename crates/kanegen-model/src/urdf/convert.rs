//! The conversion driver: the parsed URDF, resolved against the options ([`resolve`]), becomes
//! the IR (base, moving joints, bodies) and is validated.

use std::collections::HashMap;

use nalgebra::Vector3;

use super::cut::BaseCut;
use super::inertia::{Clusters, Inertial, link_inertial, merge};
use super::options::{UrdfBase, UrdfOptions, bad_option};
use super::resolved::{Ir, Resolved};
use super::transform::{Notes, Tf, clean, finite3, numbers, pose_tf, rows};
use super::tree::{Tree, is_moving, type_name};
use super::wheeled;
use crate::error::ModelErrorKind as K;
use crate::ident::sanitize_identifier;
use crate::ir::*;
use crate::limits::check_magnitude;
use crate::validate;

/// Converts a parsed URDF to a validated model and the import notes.
pub(super) fn convert(
    robot: &urdf_rs::Robot,
    file: &str,
    opts: &UrdfOptions,
) -> Result<(Model, Vec<String>), K> {
    opts.check()?;
    let mut notes = Notes::default();
    let (robot, mimics) = super::mimic::prepare(robot, opts.mimic, &mut notes);
    let robot = robot.as_ref();
    let r = resolve(robot, opts, &mut notes)?;
    let wheel = match &opts.base {
        UrdfBase::Wheeled(w) => Some((w, wheeled::wheel_geometry(w, &r, &mut notes)?)),
        UrdfBase::Fixed | UrdfBase::Floating => None,
    };
    let mut ir = Ir::new(opts.gravity);
    let base = match &wheel {
        Some((w, wg)) => wheeled::add_base(&mut ir, w, wg, &r)?,
        None => {
            ir.links.push(Link {
                name: r.tree.link(r.cut.top).name.clone(),
                mount: None,
                body: None,
            });
            ir.ir_index.insert(r.cut.top, 0);
            if r.cut.floating {
                ir.speeds.extend(crate::ir::floating_base_speeds());
                Base::Floating
            } else {
                Base::Fixed
            }
        }
    };
    add_moving_joints(&mut ir, &r);
    add_bodies(&mut ir, &r, matches!(base, Base::Fixed), &mut notes)?;
    if opts.link_frames {
        add_link_frames(&mut ir, &r);
    }
    let model = assemble(ir, base, robot, file, opts)?;
    let mut mimic_notes = Vec::new();
    let mut model = model.with_mimics(&mimics, &mut mimic_notes)?;
    if !model.mimics.is_empty() {
        model.description = format!(
            "{} ({} of them dependent: mimic joints)",
            model.description,
            model.mimics.len()
        );
    }
    mimic_notes.into_iter().for_each(|n| notes.push(n));
    for f in &opts.frames {
        if let Some(x) = f.translation.iter().find(|x| !x.is_finite()) {
            return Err(K::BadFrame {
                frame: f.name.clone(),
                detail: format!("translation entry {x} is not a finite number (metres)"),
            });
        }
        let t = f.translation.map(Length::number);
        crate::frames::add_fixed_frame(&mut model, &f.name, &f.parent, f.rotation, t, &f.name)?;
    }
    Ok((model, notes.finish()))
}

/// Applies the options to the URDF's tree: dropped links, the base cut, the checks of the kept
/// joints, the joint origins, the link inertials and the rigid clusters.
fn resolve<'a>(
    robot: &'a urdf_rs::Robot,
    opts: &UrdfOptions,
    notes: &mut Notes,
) -> Result<Resolved<'a>, K> {
    let tree = Tree::new(robot)?;
    let n = robot.links.len();
    let root = tree.root()?;
    let dropped = dropped_links(&tree, root, opts, notes)?;
    let cut = match &opts.base {
        UrdfBase::Wheeled(w) => BaseCut::wheeled(w, &tree, &dropped, notes)?,
        UrdfBase::Fixed => BaseCut::fixed_or_floating(&tree, root, false, notes),
        UrdfBase::Floating => BaseCut::fixed_or_floating(&tree, root, true, notes),
    };
    let kept = tree.preorder(cut.top, &|k| !dropped[tree.child_of(k)]);
    check_joints(
        &tree,
        &kept,
        &cut,
        matches!(opts.base, UrdfBase::Wheeled(_)),
    )?;

    // Joint origins (snapping noted once per joint).
    let mut origin: Vec<Option<Tf>> = vec![None; robot.joints.len()];
    for &l in &kept {
        if l == cut.top {
            continue;
        }
        let k = tree.parent_joint[l].expect("non-top link has a joint");
        let j = tree.joint(k);
        origin[k] = Some(pose_tf(
            &j.origin,
            opts.snap_angles,
            &format!("joint `{}` <origin>", j.name),
            notes,
        ));
    }

    // Per-link inertials (checks of the options included).
    let mut inertial: Vec<Option<Inertial>> = vec![None; n];
    for &l in &kept {
        inertial[l] = link_inertial(tree.link(l), opts, notes)?;
    }

    let clusters = Clusters::new(&tree, &kept, cut.top, cut.body, &origin);
    Ok(Resolved {
        tree,
        dropped,
        cut,
        kept,
        origin,
        inertial,
        clusters,
    })
}

/// Per link: is it removed by [`UrdfOptions::drop_links`] (with its subtree)? One note per listed
/// link.
fn dropped_links(
    tree: &Tree<'_>,
    root: usize,
    opts: &UrdfOptions,
    notes: &mut Notes,
) -> Result<Vec<bool>, K> {
    let mut dropped = vec![false; tree.parent_joint.len()];
    for name in &opts.drop_links {
        let Some(&i) = tree.index.get(name.as_str()) else {
            return Err(bad_option(
                "drop_links",
                format!("the URDF has no link `{name}`; list existing link names"),
            ));
        };
        if i == root {
            return Err(bad_option(
                "drop_links",
                format!("`{name}` is the root link and cannot be dropped"),
            ));
        }
        let sub = tree.preorder(i, &|_| true);
        let names: Vec<&str> = sub.iter().map(|&l| tree.link(l).name.as_str()).collect();
        let mass: f64 = sub.iter().map(|&l| tree.link(l).inertial.mass.value).sum();
        notes.push(format!(
            "dropped (drop_links): {} ({mass} kg in all)",
            names.join(", ")
        ));
        for l in sub {
            dropped[l] = true;
        }
    }
    Ok(dropped)
}

/// Checks the joints above the kept links (other than the top and the wheel joints), in file
/// order: supported kinds, finite numbers, a nonzero axis for moving joints.
fn check_joints(tree: &Tree<'_>, kept: &[usize], cut: &BaseCut, wheeled: bool) -> Result<(), K> {
    let mut is_kept = vec![false; tree.parent_joint.len()];
    for &l in kept {
        is_kept[l] = true;
    }
    for (k, j) in tree.joints().iter().enumerate() {
        let c = tree.child_of(k);
        if !is_kept[c] || c == cut.top || cut.wheel_joints.contains(&k) {
            continue;
        }
        use urdf_rs::JointType as J;
        match j.joint_type {
            J::Floating | J::Planar | J::Spherical => {
                let fix = match (&j.joint_type, wheeled) {
                    (J::Spherical, _) => "model it as three revolute joints with massless links between them, or make it fixed".to_owned(),
                    (_, false) => "the generator has fixed, floating and two-wheeled bases: make it fixed; a floating base is the one `floating` joint of a bare root link named `world`, or the root itself with UrdfBase::Floating; or declare a wheeled base (UrdfBase::Wheeled) whose body link hangs from it".to_owned(),
                    (_, true) => "only the joint directly above the wheeled base's body link (through fixed joints) is replaced by the base; make this one fixed".to_owned(),
                };
                return Err(K::UrdfUnsupportedJoint {
                    joint: j.name.clone(),
                    kind: type_name(&j.joint_type).into(),
                    fix,
                });
            }
            _ => {}
        }
        let axis = j.axis.xyz.0;
        if !finite3(j.origin.xyz.0) || !finite3(j.origin.rpy.0) || !finite3(axis) {
            return Err(K::UrdfBadNumber {
                element: format!("joint `{}` <origin>/<axis>", j.name),
                attribute: "xyz/rpy".into(),
                text: format!("{:?} {:?} {:?}", j.origin.xyz.0, j.origin.rpy.0, axis),
                expected: "finite numbers".into(),
            });
        }
        check_magnitude(
            || format!("URDF joint `{}` <origin xyz>", j.name),
            &j.origin.xyz.0,
        )?;
        if is_moving(&j.joint_type) && Vector3::from(axis).norm() == 0.0 {
            return Err(K::Invalid {
                item: format!("URDF joint `{}`", j.name),
                detail: "<axis xyz=\"0 0 0\"> has no direction; give a nonzero axis".into(),
            });
        }
    }
    Ok(())
}

/// Adds a frame, a joint and a speed per moving URDF joint, depth first; each joint hangs from
/// the frame of its parent link's rigid cluster.
fn add_moving_joints(ir: &mut Ir, r: &Resolved<'_>) {
    let (tree, cl) = (&r.tree, &r.clusters);
    for &l in &r.kept {
        if l == r.cut.top || r.cut.wheel_part[l] {
            continue;
        }
        let k = tree.parent_joint[l].expect("joint");
        let j = tree.joint(k);
        if !is_moving(&j.joint_type) {
            continue;
        }
        let p = tree.parent_of(k);
        let t = cl.in_rep(p).then(&r.origin[k].expect("origin"));
        let axis = Vector3::from(j.axis.xyz.0).normalize();
        let speed = ir.speeds.len();
        ir.speeds.push(Speed {
            name: sanitize_identifier(&format!("qd_{}", j.name)),
            coordinate: sanitize_identifier(&format!("q_{}", j.name)),
        });
        ir.ir_index.insert(l, ir.links.len());
        ir.links.push(Link {
            name: tree.link(l).name.clone(),
            mount: Some(Mount {
                parent: ir.ir_index[&cl.rep(p)],
                joint: Joint {
                    name: j.name.clone(),
                    kind: if j.joint_type == urdf_rs::JointType::Prismatic {
                        JointKind::Prismatic { speed }
                    } else {
                        JointKind::Revolute { speed }
                    },
                    axis: [axis.x, axis.y, axis.z].map(clean),
                    rotation: rows(&t.r),
                    translation: numbers(t.p),
                },
            }),
            body: None,
        });
    }
}

/// Adds a body-less frame for every kept link merged into its cluster's frame by fixed joints
/// (wheels excepted), mounted on that frame by a fixed joint with the link's pose in it (the
/// composition of the fixed joints' origins), so that its pose survives the inertia merge. The
/// frames are appended in depth-first order after the moving joints' frames.
fn add_link_frames(ir: &mut Ir, r: &Resolved<'_>) {
    let (tree, cl) = (&r.tree, &r.clusters);
    for &l in &r.kept {
        if r.cut.wheel_part[l] || ir.ir_index.contains_key(&l) {
            continue;
        }
        let Some(&parent) = ir.ir_index.get(&cl.rep(l)) else {
            continue;
        };
        let t = cl.in_rep(l);
        let joint = match tree.parent_joint[l] {
            Some(k) if l != r.cut.top => tree.joint(k).name.clone(),
            _ => format!("{} (fixed)", tree.link(l).name),
        };
        ir.links.push(Link {
            name: tree.link(l).name.clone(),
            mount: Some(Mount {
                parent,
                joint: Joint {
                    name: joint,
                    kind: JointKind::Fixed,
                    axis: [0.0, 0.0, 1.0],
                    rotation: rows(&t.r),
                    translation: numbers(t.p),
                },
            }),
            body: None,
        });
    }
}

/// Gives each frame the body of its rigid cluster: the merged inertia of its links about the
/// frame, with a note per merge. Links fixed to a fixed base frame carry no dynamics (a note).
fn add_bodies(ir: &mut Ir, r: &Resolved<'_>, fixed_base: bool, notes: &mut Notes) -> Result<(), K> {
    let (tree, cl) = (&r.tree, &r.clusters);
    let mut members: HashMap<usize, Vec<usize>> = HashMap::new();
    for &l in &r.kept {
        if !r.cut.wheel_part[l] {
            members.entry(cl.rep(l)).or_default().push(l);
        }
    }
    let mut rep_of_ir: Vec<Option<usize>> = vec![None; ir.links.len()];
    for (&rep, &i) in &ir.ir_index {
        rep_of_ir[i] = Some(rep);
    }
    for (li, rep) in rep_of_ir.into_iter().enumerate() {
        let Some(rep) = rep else {
            continue;
        };
        let group = &members[&rep];
        let items: Vec<(Tf, Inertial)> = group
            .iter()
            .filter_map(|&l| r.inertial[l].map(|i| (cl.in_rep(l), i)))
            .collect();
        let mass: f64 = items.iter().map(|(_, i)| i.m).sum();
        let others: Vec<&str> = group
            .iter()
            .filter(|&&l| l != rep)
            .map(|&l| tree.link(l).name.as_str())
            .collect();
        if fixed_base && li == 0 {
            if !others.is_empty() || mass > 0.0 {
                notes.push(format!(
                    "fixed to the base frame `{}` (no effect on the dynamics, {mass} kg ignored): {}",
                    tree.link(rep).name,
                    group
                        .iter()
                        .map(|&l| tree.link(l).name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ));
            }
            continue;
        }
        if !others.is_empty() {
            notes.push(format!(
                "merged into `{}` through fixed joints: {}",
                tree.link(rep).name,
                others.join(", ")
            ));
        }
        // Zero-mass links keep their rotational inertia (UrdfOptions::zero_mass_inertia).
        if items.is_empty() {
            continue;
        }
        let (m, ms, j) = merge(&items);
        let link_name = &tree.link(rep).name;
        let s = sanitize_identifier(link_name);
        let mut sym = |prefix: &str, v: f64| {
            let name = sanitize_identifier(&format!("{prefix}_{link_name}"));
            ir.param(name, v, ParamKind::Inertial)
        };
        let body = Body {
            name: s,
            mass: sym("m", m),
            first_moment: [sym("MX", ms.x), sym("MY", ms.y), sym("MZ", ms.z)],
            inertia: [
                sym("XX", j[(0, 0)]),
                sym("XY", j[(0, 1)]),
                sym("XZ", j[(0, 2)]),
                sym("YY", j[(1, 1)]),
                sym("YZ", j[(1, 2)]),
                sym("ZZ", j[(2, 2)]),
            ],
        };
        ir.links[li].body = Some(body);
    }
    Ok(())
}

/// The model from the IR: name and description, and the checks of a TOML model (names, unit
/// axes, proper rotations, positive masses, physical inertias).
fn assemble(
    ir: Ir,
    base: Base,
    robot: &urdf_rs::Robot,
    file: &str,
    opts: &UrdfOptions,
) -> Result<Model, K> {
    let name = opts.name.clone().unwrap_or_else(|| robot.name.clone());
    let description = format!(
        "imported from URDF robot `{}`: {} speeds, {} base",
        robot.name,
        ir.speeds.len(),
        match base {
            Base::Fixed => "fixed",
            Base::Wheeled(_) => "two-wheeled",
            Base::Floating => "floating",
        }
    );
    let model = Model {
        name,
        description,
        source: file.to_owned(),
        params: ir.params,
        speeds: ir.speeds,
        links: ir.links,
        base,
        gravity: Gravity {
            symbol: ir.gravity,
            direction: opts.gravity_direction,
        },
        mimics: Vec::new(),
    };
    crate::names::check(&model)?;
    for (_, _, m) in model.mounted_links() {
        validate::check_axis(&m.joint.name, m.joint.axis)?;
        validate::check_rotation(&m.joint.name, &m.joint.rotation)?;
    }
    validate::check_physics(&model, opts.inertia_tolerance)?;
    Ok(model)
}
