//! The URDF's link/joint graph as indices: the root, cycles, depth-first order.

use std::collections::{HashMap, HashSet};

use crate::error::ModelErrorKind as K;

/// The URDF name of a joint type.
pub(super) fn type_name(t: &urdf_rs::JointType) -> &'static str {
    use urdf_rs::JointType as J;
    match t {
        J::Revolute => "revolute",
        J::Continuous => "continuous",
        J::Prismatic => "prismatic",
        J::Fixed => "fixed",
        J::Floating => "floating",
        J::Planar => "planar",
        J::Spherical => "spherical",
    }
}

/// Does the joint type move with one coordinate (revolute, continuous, prismatic)?
pub(super) fn is_moving(t: &urdf_rs::JointType) -> bool {
    use urdf_rs::JointType as J;
    matches!(t, J::Revolute | J::Continuous | J::Prismatic)
}

/// The URDF as a tree of indices.
pub(super) struct Tree<'a> {
    robot: &'a urdf_rs::Robot,
    /// Link index by name.
    pub(super) index: HashMap<&'a str, usize>,
    /// Per link: the joint whose child it is.
    pub(super) parent_joint: Vec<Option<usize>>,
    /// Per link: the joints whose parent it is, in file order.
    pub(super) child_joints: Vec<Vec<usize>>,
}

impl<'a> Tree<'a> {
    /// Indexes the links and joints; typed errors for duplicate names, missing links and links
    /// with two parents.
    pub(super) fn new(robot: &'a urdf_rs::Robot) -> Result<Self, K> {
        let n = robot.links.len();
        let mut index = HashMap::new();
        for (i, l) in robot.links.iter().enumerate() {
            if index.insert(l.name.as_str(), i).is_some() {
                return Err(K::Duplicate {
                    what: "URDF link",
                    name: l.name.clone(),
                });
            }
        }
        let mut names = HashSet::new();
        let mut parent_joint: Vec<Option<usize>> = vec![None; n];
        let mut child_joints = vec![Vec::new(); n];
        for (k, j) in robot.joints.iter().enumerate() {
            if !names.insert(j.name.as_str()) {
                return Err(K::Duplicate {
                    what: "URDF joint",
                    name: j.name.clone(),
                });
            }
            let &p = index
                .get(j.parent.link.as_str())
                .ok_or_else(|| K::UrdfMissingParentLink {
                    joint: j.name.clone(),
                    parent: j.parent.link.clone(),
                })?;
            let &c = index
                .get(j.child.link.as_str())
                .ok_or_else(|| K::UrdfMissingChildLink {
                    joint: j.name.clone(),
                    child: j.child.link.clone(),
                })?;
            if let Some(first) = parent_joint[c] {
                return Err(K::UrdfTwoParents {
                    link: j.child.link.clone(),
                    first: robot.joints[first].name.clone(),
                    second: j.name.clone(),
                });
            }
            parent_joint[c] = Some(k);
            child_joints[p].push(k);
        }
        Ok(Self {
            robot,
            index,
            parent_joint,
            child_joints,
        })
    }

    /// Link `i`.
    pub(super) fn link(&self, i: usize) -> &'a urdf_rs::Link {
        &self.robot.links[i]
    }

    /// Joint `k`.
    pub(super) fn joint(&self, k: usize) -> &'a urdf_rs::Joint {
        &self.robot.joints[k]
    }

    /// All joints, in file order.
    pub(super) fn joints(&self) -> &'a [urdf_rs::Joint] {
        &self.robot.joints
    }

    /// The joint called `name`.
    pub(super) fn joint_named(&self, name: &str) -> Option<usize> {
        self.robot.joints.iter().position(|j| j.name == name)
    }

    /// The parent link of joint `k`.
    pub(super) fn parent_of(&self, k: usize) -> usize {
        self.index[self.joint(k).parent.link.as_str()]
    }

    /// The child link of joint `k`.
    pub(super) fn child_of(&self, k: usize) -> usize {
        self.index[self.joint(k).child.link.as_str()]
    }

    /// The unique root, or a typed error (no links, several roots, a cycle).
    pub(super) fn root(&self) -> Result<usize, K> {
        let roots: Vec<usize> = (0..self.robot.links.len())
            .filter(|&i| self.parent_joint[i].is_none())
            .collect();
        match roots.len() {
            0 if self.robot.links.is_empty() => Err(K::UrdfParse {
                detail: "the <robot> has no <link>".into(),
            }),
            0 => Err(self.cycle_from(0)),
            1 => {
                let root = roots[0];
                let reached = self.preorder(root, &|_| true);
                if reached.len() < self.robot.links.len() {
                    let lost = (0..self.robot.links.len())
                        .find(|i| !reached.contains(i))
                        .expect("an unreached link");
                    return Err(self.cycle_from(lost));
                }
                Ok(root)
            }
            _ => Err(K::UrdfTwoRoots {
                roots: roots.iter().map(|&i| self.link(i).name.clone()).collect(),
            }),
        }
    }

    /// Walks up from a link that is not reachable from the root to a joint on its cycle.
    fn cycle_from(&self, link: usize) -> K {
        let mut seen = vec![false; self.robot.links.len()];
        let mut l = link;
        while !seen[l] {
            seen[l] = true;
            l = self.parent_of(self.parent_joint[l].expect("every link on a cycle has a parent"));
        }
        let k = self.parent_joint[l].expect("on the cycle");
        K::Cycle {
            joint: self.joint(k).name.clone(),
            frame: self.joint(k).child.link.clone(),
        }
    }

    /// Links of the subtree of `top` in depth-first preorder (children in joint file order),
    /// descending only through joints `k` with `keep(k)`.
    pub(super) fn preorder(&self, top: usize, keep: &dyn Fn(usize) -> bool) -> Vec<usize> {
        let mut out = Vec::new();
        let mut stack = vec![top];
        while let Some(l) = stack.pop() {
            out.push(l);
            for &k in self.child_joints[l].iter().rev() {
                if keep(k) {
                    stack.push(self.child_of(k));
                }
            }
        }
        out
    }
}
