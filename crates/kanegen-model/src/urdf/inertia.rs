//! Link inertials: reading and checking them (the absurd-inertia guard), and merging the links
//! joined by fixed joints into one body.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use super::transform::{Notes, Tf, finite3, rpy_matrix};
use super::tree::Tree;
use super::{AbsurdInertia, UrdfOptions};
use crate::error::ModelErrorKind as K;

/// A link's own inertial data in its frame: mass, centre of mass, inertia about the COM.
#[derive(Debug, Clone, Copy)]
pub(super) struct Inertial {
    /// Mass.
    pub(super) m: f64,
    /// Centre of mass.
    pub(super) c: Vector3<f64>,
    /// Inertia about the centre of mass.
    pub(super) ig: Matrix3<f64>,
}

/// Mass, first moment and inertia about the frame origin of a set of inertials given with their
/// poses in that frame.
pub(super) fn merge(items: &[(Tf, Inertial)]) -> (f64, Vector3<f64>, Matrix3<f64>) {
    let mut m = 0.0;
    let mut ms = Vector3::zeros();
    let mut j = Matrix3::zeros();
    for (t, i) in items {
        let c = t.r * i.c + t.p;
        m += i.m;
        ms += c * i.m;
        j += t.r * i.ig * t.r.transpose()
            + (Matrix3::identity() * c.norm_squared() - c * c.transpose()) * i.m;
    }
    (m, ms, j)
}

/// A link's inertial data (`None` for zero mass), after the checks of the options.
pub(super) fn link_inertial(
    link: &urdf_rs::Link,
    opts: &UrdfOptions,
    notes: &mut Notes,
) -> Result<Option<Inertial>, K> {
    let inertial = &link.inertial;
    let m = inertial.mass.value;
    let t = &inertial.inertia;
    let nums = [m, t.ixx, t.ixy, t.ixz, t.iyy, t.iyz, t.izz];
    let element = format!("link `{}` <inertial>", link.name);
    if !nums.iter().all(|x| x.is_finite())
        || !finite3(inertial.origin.xyz.0)
        || !finite3(inertial.origin.rpy.0)
    {
        return Err(K::UrdfBadNumber {
            element,
            attribute: "mass/inertia/origin".into(),
            text: format!(
                "m {m}, I {nums:?}, xyz {:?}, rpy {:?}",
                inertial.origin.xyz.0, inertial.origin.rpy.0
            ),
            expected: "finite numbers".into(),
        });
    }
    if m < 0.0 {
        return Err(K::NonPositiveMass {
            body: link.name.clone(),
            symbol: "<mass value>".into(),
            value: m,
        });
    }
    let ic = Matrix3::new(
        t.ixx, t.ixy, t.ixz, t.ixy, t.iyy, t.iyz, t.ixz, t.iyz, t.izz,
    );
    if m == 0.0 {
        if ic != Matrix3::zeros() {
            notes.push(format!(
                "link `{}`: zero mass with a nonzero inertia; the inertia is ignored",
                link.name
            ));
        }
        return Ok(None);
    }
    let rot = rpy_matrix(
        inertial.origin.rpy.0,
        opts.snap_angles,
        &format!("link `{}` <inertial><origin>", link.name),
        notes,
    );
    let ig = rot * ic * rot.transpose();
    let lmax = SymmetricEigen::new(ig).eigenvalues.max();
    if lmax > 0.0 {
        let radius = (lmax / m).sqrt();
        if radius > opts.max_radius_of_gyration {
            let what = format!(
                "link `{}`: radius of gyration {radius:.3} m (mass {m} kg, largest principal moment {lmax:.4e} kg·m²) exceeds {} m",
                link.name, opts.max_radius_of_gyration
            );
            match opts.absurd_inertia {
                AbsurdInertia::Error => {
                    return Err(K::UrdfAbsurdInertia {
                        link: link.name.clone(),
                        mass: m,
                        moment: lmax,
                        radius,
                        limit: opts.max_radius_of_gyration,
                    });
                }
                AbsurdInertia::Drop => {
                    notes.push(format!("{what}: inertia dropped"));
                    return Ok(None);
                }
                AbsurdInertia::Keep => notes.push(format!("{what}: kept as written")),
            }
        }
    }
    Ok(Some(Inertial {
        m,
        c: Vector3::from(inertial.origin.xyz.0),
        ig,
    }))
}

/// The rigid clusters (links joined by fixed joints) of the kept tree.
pub(super) struct Clusters {
    /// The kept tree's top link.
    top: usize,
    /// The frame of the top cluster: `top` (fixed base) or the wheeled base's body link.
    pub(super) body: usize,
    /// Per link: the top link of its cluster (`usize::MAX` for links that are not kept).
    pub(super) cluster_top: Vec<usize>,
    /// Per link: its pose in its cluster top's frame.
    pub(super) in_top: Vec<Tf>,
}

impl Clusters {
    /// Each kept link's cluster top (the link below the nearest moving joint) and its pose in
    /// that top's frame, from the joint origins; the cluster's frame (its representative) is the
    /// top, except for the wheeled body's cluster, whose frame is the body link.
    pub(super) fn new(
        tree: &Tree<'_>,
        kept: &[usize],
        top: usize,
        body: usize,
        origin: &[Option<Tf>],
    ) -> Self {
        let n = tree.parent_joint.len();
        let mut cl = Clusters {
            top,
            body,
            cluster_top: vec![usize::MAX; n],
            in_top: vec![Tf::identity(); n],
        };
        for &l in kept {
            match tree.parent_joint[l].filter(|_| l != top) {
                Some(k) if tree.joint(k).joint_type == urdf_rs::JointType::Fixed => {
                    let p = tree.parent_of(k);
                    cl.cluster_top[l] = cl.cluster_top[p];
                    cl.in_top[l] = cl.in_top[p].then(&origin[k].expect("origin"));
                }
                _ => cl.cluster_top[l] = l,
            }
        }
        cl
    }

    /// The link whose frame is the frame of `l`'s cluster.
    pub(super) fn rep(&self, l: usize) -> usize {
        let t = self.cluster_top[l];
        if t == self.top { self.body } else { t }
    }

    /// The pose of link `l` in its cluster's frame.
    pub(super) fn in_rep(&self, l: usize) -> Tf {
        self.in_top[self.rep(l)].inverse().then(&self.in_top[l])
    }
}
