//! `<mimic>` joints in the URDF, per [`MimicMode`]: the constraints to keep (exact), or the file
//! rewritten with the joints independent or fixed.

use std::borrow::Cow;

use nalgebra::{Rotation3, Unit, Vector3};

use super::transform::Notes;
use super::tree::is_moving;
use crate::mimic::{MimicMode, MimicSpec};

/// The robot as the conversion should see it and the exact constraints to apply afterwards.
/// `Exact`: the file unchanged and one [`MimicSpec`] per moving joint with a `<mimic>`, in file
/// order. `Independent`: `<mimic>` removed. `Fixed`: each such joint made fixed at its offset
/// (`origin · Rot(axis, offset)`, or a shift along the axis for a prismatic joint). One note per
/// joint in the latter two modes.
pub(super) fn prepare<'a>(
    robot: &'a urdf_rs::Robot,
    mode: MimicMode,
    notes: &mut Notes,
) -> (Cow<'a, urdf_rs::Robot>, Vec<MimicSpec>) {
    let has = |j: &urdf_rs::Joint| j.mimic.is_some() && is_moving(&j.joint_type);
    if !robot.joints.iter().any(has) {
        return (Cow::Borrowed(robot), Vec::new());
    }
    if mode == MimicMode::Exact {
        let specs = robot
            .joints
            .iter()
            .filter(|j| has(j))
            .filter_map(|j| {
                j.mimic.as_ref().map(|m| MimicSpec {
                    joint: j.name.clone(),
                    master: m.joint.clone(),
                    multiplier: m.multiplier.unwrap_or(1.0),
                    offset: m.offset.unwrap_or(0.0),
                })
            })
            .collect();
        return (Cow::Borrowed(robot), specs);
    }
    let mut robot = robot.clone();
    for j in robot.joints.iter_mut() {
        if !has(j) {
            continue;
        }
        let Some(m) = j.mimic.take() else { continue };
        if mode == MimicMode::Independent {
            notes.push(format!(
                "mimic joint `{}` (of `{}`) imported as an independent coordinate (UrdfOptions::mimic = Independent)",
                j.name, m.joint
            ));
            continue;
        }
        let b = m.offset.unwrap_or(0.0);
        let axis = Vector3::from(j.axis.xyz.0);
        if b != 0.0 && b.is_finite() && axis.norm() > 0.0 {
            let axis = Unit::new_normalize(axis);
            let [r, p, y] = j.origin.rpy.0;
            let rot = Rotation3::from_euler_angles(r, p, y);
            if j.joint_type == urdf_rs::JointType::Prismatic {
                let shift = rot * axis.into_inner() * b;
                for (x, d) in j.origin.xyz.0.iter_mut().zip(shift.iter()) {
                    *x += d;
                }
            } else {
                let (r, p, y) = (rot * Rotation3::from_axis_angle(&axis, b)).euler_angles();
                j.origin.rpy.0 = [r, p, y];
            }
        }
        notes.push(format!(
            "mimic joint `{}` (of `{}`) fixed at its offset {b} (UrdfOptions::mimic = Fixed)",
            j.name, m.joint
        ));
        j.joint_type = urdf_rs::JointType::Fixed;
    }
    (Cow::Owned(robot), Vec::new())
}
