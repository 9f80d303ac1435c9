//! Link inertials: reading and checking them (the absurd-inertia guard), and merging the links
//! joined by fixed joints into one body.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use super::options::{AbsurdInertia, NonPhysicalInertia, UrdfOptions, ZeroMassInertia};
use super::transform::{Notes, Tf, finite3, rpy_matrix};
use super::tree::Tree;
use crate::error::ModelErrorKind as K;
use crate::limits::check_magnitude;
use crate::validate;

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

/// A link's inertial data (`None` for none: no mass and no inertia, or dropped by the options),
/// after the checks of the options: finite numbers, a mass ≥ 0, a physical inertia about the
/// centre of mass (zero to rounding below [`UrdfOptions::inertia_floor`]; otherwise up to
/// [`UrdfOptions::inertia_tolerance`], as [`UrdfOptions::non_physical_inertia`] says), a plausible radius of gyration, and the
/// inertia of a zero-mass link ([`UrdfOptions::zero_mass_inertia`]).
pub(super) fn link_inertial(
    link: &urdf_rs::Link,
    opts: &UrdfOptions,
    notes: &mut Notes,
) -> Result<Option<Inertial>, K> {
    let inertial = &link.inertial;
    let m = inertial.mass.value;
    let t = &inertial.inertia;
    let nums = [m, t.ixx, t.ixy, t.ixz, t.iyy, t.iyz, t.izz];
    if !nums.iter().all(|x| x.is_finite())
        || !finite3(inertial.origin.xyz.0)
        || !finite3(inertial.origin.rpy.0)
    {
        return Err(K::UrdfBadNumber {
            element: format!("link `{}` <inertial>", link.name),
            attribute: "mass/inertia/origin".into(),
            text: format!(
                "m {m}, I {nums:?}, xyz {:?}, rpy {:?}",
                inertial.origin.xyz.0, inertial.origin.rpy.0
            ),
            expected: "finite numbers".into(),
        });
    }
    check_magnitude(
        || {
            format!(
                "URDF link `{}` <inertial> (mass, inertia, origin xyz)",
                link.name
            )
        },
        &[&nums[..], &inertial.origin.xyz.0[..]].concat(),
    )?;
    let unphysical = |detail: String, fix: &str| K::UrdfNonPhysicalInertial {
        link: link.name.clone(),
        detail,
        fix: fix.to_owned(),
    };
    if m < 0.0 {
        return Err(unphysical(
            format!("<mass value=\"{m}\"> is negative"),
            "give the link's mass in kg (≥ 0)",
        ));
    }
    let ic = Matrix3::new(
        t.ixx, t.ixy, t.ixz, t.ixy, t.iyy, t.iyz, t.ixz, t.iyz, t.izz,
    );
    if m == 0.0 && ic == Matrix3::zeros() {
        return Ok(None);
    }
    let rot = rpy_matrix(
        inertial.origin.rpy.0,
        opts.snap_angles,
        &format!("link `{}` <inertial><origin>", link.name),
        notes,
    );
    let ig = physical_inertia(link, rot * ic * rot.transpose(), opts, notes)?;
    if m == 0.0 && ig == Matrix3::zeros() {
        return Ok(None);
    }
    if m == 0.0 {
        let what = format!(
            "link `{}`: zero mass with a nonzero rotational inertia (ixx {}, iyy {}, izz {})",
            link.name, t.ixx, t.iyy, t.izz
        );
        if opts.zero_mass_inertia == ZeroMassInertia::Drop {
            notes.push(format!("{what}: dropped (zero_mass_inertia = Drop)"));
            return Ok(None);
        }
        notes.push(format!("{what}: kept as a body with m = 0"));
    } else if !absurd_inertia_kept(link, m, &ig, opts, notes)? {
        return Ok(None);
    }
    Ok(Some(Inertial {
        m,
        c: Vector3::from(inertial.origin.xyz.0),
        ig,
    }))
}

/// The inertia `ig` about the centre of mass of `link`: zero if it is zero to rounding (every
/// principal moment within [`UrdfOptions::inertia_floor`] of 0), as written if it is physical
/// (positive semi-definite, triangle inequality; point masses and rods are), otherwise as
/// [`UrdfOptions::non_physical_inertia`] says up to [`UrdfOptions::inertia_tolerance`] (kept with
/// a note, repaired with a note, or refused); beyond the tolerance the error, in URDF terms.
fn physical_inertia(
    link: &urdf_rs::Link,
    ig: Matrix3<f64>,
    opts: &UrdfOptions,
    notes: &mut Notes,
) -> Result<Matrix3<f64>, K> {
    let moments = validate::principal_moments(&ig);
    if moments.iter().all(|l| l.abs() <= opts.inertia_floor) {
        return Ok(Matrix3::zeros());
    }
    let (violation, what) = validate::inertia_violation(moments);
    if violation <= validate::TOLERANCE {
        return Ok(ig);
    }
    let t = &link.inertial.inertia;
    let [a, b, c] = moments;
    let detail = format!(
        "the inertia (ixx {}, ixy {}, ixz {}, iyy {}, iyz {}, izz {}) has the principal moments \
         {a:.6e}, {b:.6e}, {c:.6e} about the centre of mass: {what}, by {:.2} % of the largest",
        t.ixx,
        t.ixy,
        t.ixz,
        t.iyy,
        t.iyz,
        t.izz,
        violation * 100.0
    );
    if violation > opts.inertia_tolerance || opts.non_physical_inertia == NonPhysicalInertia::Error
    {
        let limit = if opts.non_physical_inertia == NonPhysicalInertia::Error {
            "non_physical_inertia is Error".to_owned()
        } else {
            format!(
                "the violation exceeds UrdfOptions::inertia_tolerance ({})",
                opts.inertia_tolerance
            )
        };
        return Err(K::UrdfNonPhysicalInertial {
            link: link.name.clone(),
            detail,
            fix: format!(
                "refused because {limit}; correct ixx … izz (each principal moment ≥ 0 and at \
                 most the sum of the other two), or load it as written (NonPhysicalInertia::Note) \
                 or repaired (NonPhysicalInertia::Repair) with inertia_tolerance at least {:.4}",
                (violation * 1e4 - 1e-6).ceil() / 1e4
            ),
        });
    }
    if opts.non_physical_inertia == NonPhysicalInertia::Note {
        notes.push(format!("link `{}`: {detail}; kept as written", link.name));
        return Ok(ig);
    }
    // Repair: the nearest physical principal moments, principal axes kept.
    let e = SymmetricEigen::new(ig);
    let mut order = [0, 1, 2];
    order.sort_by(|&i, &j| e.eigenvalues[i].total_cmp(&e.eigenvalues[j]));
    let [l1, l2, l3] = order.map(|i| e.eigenvalues[i].max(0.0));
    let d = ((l3 - l1 - l2) / 3.0).max(0.0);
    let fixed = [l1 + d, l2 + d, l3 - d];
    let mut lambda = Vector3::zeros();
    for (k, &i) in order.iter().enumerate() {
        lambda[i] = fixed[k];
    }
    notes.push(format!(
        "link `{}`: {detail}; repaired to the principal moments {:.6e}, {:.6e}, {:.6e}",
        link.name, fixed[0], fixed[1], fixed[2]
    ));
    Ok(e.eigenvectors * Matrix3::from_diagonal(&lambda) * e.eigenvectors.transpose())
}

/// Whether a link of mass `m > 0` keeps its inertia `ig` under the radius-of-gyration guard
/// ([`UrdfOptions::max_radius_of_gyration`], [`AbsurdInertia`]); the error if it is absurd.
fn absurd_inertia_kept(
    link: &urdf_rs::Link,
    m: f64,
    ig: &Matrix3<f64>,
    opts: &UrdfOptions,
    notes: &mut Notes,
) -> Result<bool, K> {
    let lmax = SymmetricEigen::new(*ig).eigenvalues.max();
    let radius = (lmax.max(0.0) / m).sqrt();
    if radius <= opts.max_radius_of_gyration {
        return Ok(true);
    }
    let what = format!(
        "link `{}`: radius of gyration {radius:.3} m (mass {m} kg, largest principal moment {lmax:.4e} kg·m²) exceeds {} m",
        link.name, opts.max_radius_of_gyration
    );
    match opts.absurd_inertia {
        AbsurdInertia::Error => Err(K::UrdfAbsurdInertia {
            link: link.name.clone(),
            mass: m,
            moment: lmax,
            radius,
            limit: opts.max_radius_of_gyration,
        }),
        AbsurdInertia::Drop => {
            notes.push(format!("{what}: inertia dropped"));
            Ok(false)
        }
        AbsurdInertia::Keep => {
            notes.push(format!("{what}: kept as written"));
            Ok(true)
        }
    }
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
