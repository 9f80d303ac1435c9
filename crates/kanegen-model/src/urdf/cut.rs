//! Where the kept tree starts: the URDF root for a fixed base, or the body link below the
//! `floating`/`planar` joint that a wheeled base replaces, with the wheel joints and subtrees.

use super::options::{WheeledBaseSpec, bad_option};
use super::transform::Notes;
use super::tree::{Tree, type_name};
use crate::error::ModelErrorKind as K;

/// Where the kept tree starts, which link is the body and which links are wheels.
pub(super) struct BaseCut {
    /// The top of the kept tree: the URDF root, or the link below the `floating` or `planar`
    /// joint that the wheeled base replaces.
    pub(super) top: usize,
    /// The wheeled base's body link; `top` for a fixed base.
    pub(super) body: usize,
    /// The left and right wheel joints (none for a fixed base).
    pub(super) wheel_joints: Vec<usize>,
    /// Per link: is it a wheel link or fixed to one?
    pub(super) wheel_part: Vec<bool>,
    /// Whether the base is floating (declared, or a `floating` joint below a bare root).
    pub(super) floating: bool,
}

impl BaseCut {
    /// A fixed base: the kept tree starts at the URDF root; no wheels.
    pub(super) fn fixed(root: usize, links: usize) -> Self {
        Self {
            top: root,
            body: root,
            wheel_joints: Vec::new(),
            wheel_part: vec![false; links],
            floating: false,
        }
    }

    /// The kept tree of a fixed base (`declared_floating` false) or a floating one: a root link
    /// named `world`, without inertia, whose only joint is `floating` is cut off and its child
    /// becomes the floating base frame, declared or not (noted); otherwise the URDF root is the
    /// base frame, floating if declared.
    pub(super) fn fixed_or_floating(
        tree: &Tree<'_>,
        root: usize,
        declared_floating: bool,
        notes: &mut Notes,
    ) -> Self {
        let links = tree.parent_joint.len();
        let mut cut = Self::fixed(root, links);
        cut.floating = declared_floating;
        if let [k] = tree.child_joints[root][..]
            && tree.link(root).name == "world"
            && tree.joint(k).joint_type == urdf_rs::JointType::Floating
            && tree.link(root).inertial.mass.value == 0.0
        {
            let child = tree.child_of(k);
            notes.push(format!(
                "floating joint `{}` from `{}` gives the floating base: `{}` is the base frame",
                tree.joint(k).name,
                tree.link(root).name,
                tree.link(child).name
            ));
            cut.top = child;
            cut.body = child;
            cut.floating = true;
        }
        cut
    }

    /// Resolves the wheeled base declaration against the tree: the body link, the cut above it,
    /// the wheel joints and their subtrees.
    pub(super) fn wheeled(
        w: &WheeledBaseSpec,
        tree: &Tree<'_>,
        dropped: &[bool],
        notes: &mut Notes,
    ) -> Result<Self, K> {
        let (body, top) = body_and_top(w, tree, dropped, notes)?;
        let mut cut = Self {
            top,
            body,
            wheel_joints: Vec::new(),
            wheel_part: vec![false; tree.parent_joint.len()],
            floating: false,
        };
        for (option, name) in [
            ("base.left_wheel_joint", &w.left_wheel_joint),
            ("base.right_wheel_joint", &w.right_wheel_joint),
        ] {
            cut.add_wheel(option, name, tree, dropped)?;
        }
        if cut.wheel_part[body] {
            return Err(bad_option(
                "base.body_link",
                format!("`{}` is part of a wheel", w.body_link),
            ));
        }
        Ok(cut)
    }

    /// Adds the wheel joint `name` (declared as `option`) and marks its subtree.
    fn add_wheel(
        &mut self,
        option: &str,
        name: &str,
        tree: &Tree<'_>,
        dropped: &[bool],
    ) -> Result<(), K> {
        let Some(k) = tree.joint_named(name) else {
            return Err(bad_option(
                option,
                format!("the URDF has no joint `{name}`"),
            ));
        };
        let j = tree.joint(k);
        if !matches!(
            j.joint_type,
            urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous
        ) {
            return Err(bad_option(
                option,
                format!(
                    "`{name}` is a {} joint; a wheel joint is revolute or continuous",
                    type_name(&j.joint_type)
                ),
            ));
        }
        let c = tree.child_of(k);
        if dropped[c] {
            return Err(bad_option(
                option,
                format!("the wheel link of `{name}` is dropped by drop_links"),
            ));
        }
        if self.wheel_joints.contains(&k) {
            return Err(bad_option(
                option,
                "the left and right wheel joints must differ".into(),
            ));
        }
        for l in tree.preorder(c, &|_| true) {
            self.wheel_part[l] = true;
            for &kk in &tree.child_joints[l] {
                let jj = tree.joint(kk);
                if jj.joint_type != urdf_rs::JointType::Fixed && !dropped[tree.child_of(kk)] {
                    return Err(bad_option(
                        option,
                        format!(
                            "the {} joint `{}` hangs below the wheel; only fixed joints may (drop its link with drop_links)",
                            type_name(&jj.joint_type),
                            jj.name
                        ),
                    ));
                }
            }
        }
        self.wheel_joints.push(k);
        Ok(())
    }
}

/// The body link and the top of the kept tree: the URDF root if the body is fixed to it, or the
/// link below the `floating` or `planar` joint above the body (through fixed joints), which the
/// base replaces (the links above it are discarded, with a note).
fn body_and_top(
    w: &WheeledBaseSpec,
    tree: &Tree<'_>,
    dropped: &[bool],
    notes: &mut Notes,
) -> Result<(usize, usize), K> {
    let &body = tree.index.get(w.body_link.as_str()).ok_or_else(|| {
        bad_option(
            "base.body_link",
            format!("the URDF has no link `{}`", w.body_link),
        )
    })?;
    if dropped[body] {
        return Err(bad_option(
            "base.body_link",
            format!("`{}` is dropped by drop_links", w.body_link),
        ));
    }
    let mut l = body;
    while let Some(k) = tree.parent_joint[l] {
        let j = tree.joint(k);
        use urdf_rs::JointType as J;
        match j.joint_type {
            J::Fixed => l = tree.parent_of(k),
            J::Floating | J::Planar => {
                let above: Vec<&str> = (0..tree.parent_joint.len())
                    .filter(|i| !tree.preorder(l, &|_| true).contains(i))
                    .map(|i| tree.link(i).name.as_str())
                    .collect();
                notes.push(format!(
                    "{} joint `{}` replaced by the wheeled base; links above it discarded: {}",
                    type_name(&j.joint_type),
                    j.name,
                    above.join(", ")
                ));
                return Ok((body, l));
            }
            _ => {
                return Err(bad_option(
                    "base.body_link",
                    format!(
                        "`{}` hangs from the {} joint `{}`; the body of a two-wheeled base must be fixed to the URDF root (fixed joints only) or hang from a floating or planar joint, which the base replaces",
                        w.body_link,
                        type_name(&j.joint_type),
                        j.name
                    ),
                ));
            }
        }
    }
    // Fixed joints all the way up: `l` is the root.
    Ok((body, l))
}
