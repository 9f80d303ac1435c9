//! Typed errors of model loading and validation.

use thiserror::Error;

/// A model file could not be loaded: where ([`ModelError::file`]) and what ([`ModelError::kind`]).
#[derive(Debug, Error)]
#[error("{file}: {kind}")]
pub struct ModelError {
    /// The description file (or the label given to an in-memory description).
    pub file: String,
    /// What is wrong, naming the item and the fix.
    pub kind: ModelErrorKind,
}

impl ModelError {
    pub(crate) fn new(file: &str, kind: ModelErrorKind) -> Self {
        Self {
            file: file.to_owned(),
            kind,
        }
    }
}

/// A name that cannot be used in generated code: which item, its spelling, why and the fix
/// (the detail of [`ModelErrorKind::BadName`]).
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("{item}: `{name}` {problem}; {fix}")]
pub struct BadName {
    /// What the name names (``speed of joint `q2` ``, `parameter`, `model name`).
    pub item: String,
    /// The name as written (for a URDF: after sanitising).
    pub name: String,
    /// Why it cannot be used.
    pub problem: String,
    /// How to fix it.
    pub fix: String,
}

/// What is wrong with a description. Each message names the offending item and how to fix it.
///
/// The error of a file that cannot be read keeps the [`std::io::Error`] as its source.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ModelErrorKind {
    /// The file could not be read (the message repeats the I/O error, which is also the source).
    #[error("cannot read the file: {0}")]
    Io(#[source] std::io::Error),
    /// The description is larger than the loaders accept (a robot description is a few hundred
    /// kilobytes; meshes are separate files): refused before it is read or parsed.
    #[error(
        "the description is {bytes} bytes, more than the {limit} bytes a description may have; check that this is the robot description (meshes and other data belong in files of their own)"
    )]
    TooLarge {
        /// Its size in bytes.
        bytes: u64,
        /// The largest size accepted ([`crate::MAX_DESCRIPTION_BYTES`]).
        limit: u64,
    },
    /// URDF elements are nested deeper than the importer accepts (a URDF needs about five
    /// levels): found by a streaming pre-check, before the recursive URDF parser could overflow
    /// its stack.
    #[error(
        "URDF elements are nested more than {limit} levels deep (at <{element}>); a URDF nests <robot>, <link>/<joint> and their few levels of content: check the XML"
    )]
    UrdfTooDeep {
        /// The element that is one level too deep.
        element: String,
        /// The deepest nesting accepted.
        limit: usize,
    },
    /// The file is not valid TOML, or does not have the shape of a model description.
    #[error("malformed description: {0}")]
    Syntax(String),
    /// A URDF file could not be parsed or converted.
    #[error("URDF: {0}")]
    Urdf(String),
    /// A joint names a parent frame that no joint creates and that is not the base frame.
    #[error(
        "joint `{joint}`: parent frame `{parent}` is not defined; it must be the base frame or the child of another joint"
    )]
    UnknownParent {
        /// The joint.
        joint: String,
        /// The parent frame it names.
        parent: String,
    },
    /// A body is attached to a frame that does not exist.
    #[error(
        "body `{body}`: frame `{frame}` is not defined; attach the body to the base frame or a joint's child frame"
    )]
    UnknownFrame {
        /// The body.
        body: String,
        /// The frame it names.
        frame: String,
    },
    /// Two items of the same kind share a name.
    #[error("{what} `{name}` is defined twice; names must be unique")]
    Duplicate {
        /// Which kind of item (frame, joint, body, speed, parameter).
        what: &'static str,
        /// The repeated name.
        name: String,
    },
    /// The joints do not form a tree rooted at the base frame.
    #[error(
        "joint `{joint}`: frame `{frame}` is not reachable from the base frame (the joints form a cycle); every frame needs a chain of joints back to the base"
    )]
    Cycle {
        /// A joint on the cycle.
        joint: String,
        /// Its child frame.
        frame: String,
    },
    /// A joint's child frame is the base frame.
    #[error("joint `{joint}`: the base frame `{frame}` cannot be a joint's child")]
    BaseAsChild {
        /// The joint.
        joint: String,
        /// The base frame.
        frame: String,
    },
    /// A rotation matrix is not orthonormal or has determinant −1.
    #[error(
        "joint `{joint}`: rotation is not a proper rotation ({detail}); give iAj(0) row by row with orthonormal rows and determinant +1"
    )]
    BadRotation {
        /// The joint.
        joint: String,
        /// What failed, with the numbers.
        detail: String,
    },
    /// A joint axis is not a unit vector.
    #[error("joint `{joint}`: axis {axis:?} is not a unit vector (norm {norm}); normalise it")]
    AxisNotUnit {
        /// The joint.
        joint: String,
        /// The axis as given.
        axis: [f64; 3],
        /// Its norm.
        norm: f64,
    },
    /// A body's mass is negative or not a number, or zero with a nonzero first moment.
    #[error(
        "body `{body}`: mass `{symbol}` = {value} must be positive (or zero for a body without first moment, MX = MY = MZ = 0)"
    )]
    NonPositiveMass {
        /// The body.
        body: String,
        /// The mass symbol.
        symbol: String,
        /// Its value.
        value: f64,
    },
    /// The inertia about the centre of mass is not positive definite or breaks the triangle inequality.
    #[error(
        "body `{body}`: inertia about the centre of mass is not physical ({detail}); principal moments must be ≥ 0 and each at most the sum of the other two (check the frame-origin inertia XX..ZZ against m and MX..MZ)"
    )]
    NonPhysicalInertia {
        /// The body.
        body: String,
        /// Principal moments and which condition failed.
        detail: String,
    },
    /// A symbol used by a joint, body, base or gravity has no value in `[parameters]`.
    #[error("{item}: symbol `{symbol}` has no value; add `{symbol} = <value>` to [parameters]")]
    UndefinedSymbol {
        /// The item that uses the symbol.
        item: String,
        /// The missing symbol.
        symbol: String,
    },
    /// A parameter that is declared but that nothing uses (most often a misspelt name).
    #[error(
        "parameter `{name}` is declared but not used by any joint, body, base or gravity; remove it or correct its name"
    )]
    UnusedParameter {
        /// The parameter.
        name: String,
    },
    /// A parameter value is not a finite number.
    #[error("parameter `{name}` = {value} is not a finite number")]
    NonFiniteParameter {
        /// The parameter.
        name: String,
        /// Its value.
        value: f64,
    },
    /// A number of the description is finite but absurdly large: a parameter value, a constant
    /// of a joint's translation, or a URDF mass, inertia or origin exceeds
    /// [`MAX_PARAMETER_MAGNITUDE`](crate::MAX_PARAMETER_MAGNITUDE) in magnitude (in SI units, no
    /// robot has such a mass, length or inertia; the dynamics would overflow or lose every other
    /// digit).
    #[error(
        "{item} = {value:e} is absurdly large: its magnitude exceeds {limit:e} (SI units: kg, m, kg·m, kg·m²); correct the value (a unit slip such as grams or millimetres, or a mistyped exponent)"
    )]
    AbsurdValue {
        /// The number: `` parameter `m_b` ``, `` joint `j` translation (x) `` or
        /// `` URDF joint `j` <origin xyz> ``.
        item: String,
        /// Its value.
        value: f64,
        /// The limit, [`MAX_PARAMETER_MAGNITUDE`](crate::MAX_PARAMETER_MAGNITUDE).
        limit: f64,
    },
    /// A wheel constant of the wheeled base is not physical (`R` or `L` not positive, `mw`,
    /// `YYw` or `ZZw` negative).
    #[error(
        "wheeled base: `{symbol}` = {value} is {what} and must be {bound}; correct its value in [parameters] (URDF: in the wheel links or the WheeledBaseSpec)"
    )]
    NonPhysicalWheel {
        /// The parameter.
        symbol: String,
        /// Its value.
        value: f64,
        /// What it is (`the wheel radius`).
        what: &'static str,
        /// `positive` or `≥ 0`.
        bound: &'static str,
    },
    /// A length entry is neither a finite number nor `[-]SYMBOL`.
    #[error(
        "joint `{joint}`: translation entry `{text}` is neither a finite number nor a length symbol such as `L1` or `-L2`"
    )]
    BadLength {
        /// The joint.
        joint: String,
        /// The entry as written.
        text: String,
    },
    /// A generalized speed is driven by two joints (or a joint and the base).
    #[error(
        "speed `{speed}` is driven twice, by {first} and by {second}; each speed is driven exactly once"
    )]
    SpeedTwice {
        /// The speed.
        speed: String,
        /// The first driver.
        first: String,
        /// The second driver.
        second: String,
    },
    /// A generalized speed listed in `[model] speeds` is driven by no joint and not by the base.
    #[error("speed `{speed}` is listed in [model] speeds but no joint or base drives it")]
    SpeedNever {
        /// The speed.
        speed: String,
    },
    /// A joint or the base names a speed that is not listed in `[model] speeds`.
    #[error(
        "{item}: speed `{speed}` is not listed in [model] speeds; add it there (the list fixes the order of u)"
    )]
    UnknownSpeed {
        /// The joint or base.
        item: String,
        /// The speed.
        speed: String,
    },
    /// A moving joint without a speed, or a fixed joint with one.
    #[error("joint `{joint}`: {detail}")]
    JointSpeed {
        /// The joint.
        joint: String,
        /// What is wrong.
        detail: String,
    },
    /// The text is not a readable URDF: XML syntax or nesting, or a missing required element.
    #[error(
        "not a readable URDF: {detail}; check the XML (every element closed, one <robot> root) and that every <joint> has a type, <parent link> and <child link>"
    )]
    UrdfParse {
        /// The parser's message.
        detail: String,
    },
    /// A URDF joint names a parent link that the file does not define.
    #[error(
        "URDF joint `{joint}`: parent link `{parent}` is not defined; add <link name=\"{parent}\"/> or correct <parent link=\"...\"/>"
    )]
    UrdfMissingParentLink {
        /// The joint.
        joint: String,
        /// The link it names as parent.
        parent: String,
    },
    /// A URDF joint names a child link that the file does not define.
    #[error(
        "URDF joint `{joint}`: child link `{child}` is not defined; add <link name=\"{child}\"/> or correct <child link=\"...\"/>"
    )]
    UrdfMissingChildLink {
        /// The joint.
        joint: String,
        /// The link it names as child.
        child: String,
    },
    /// A URDF link is the child of two joints.
    #[error(
        "URDF link `{link}` is the child of two joints, `{first}` and `{second}`; a URDF is a tree: give each link at most one parent joint"
    )]
    UrdfTwoParents {
        /// The link.
        link: String,
        /// The first joint naming it as child.
        first: String,
        /// The second.
        second: String,
    },
    /// More than one URDF link is no joint's child.
    #[error(
        "URDF has {} root links ({}), i.e. links that are no joint's child; a URDF tree has exactly one root: attach the others with a joint (`fixed` if rigid) or remove them",
        .roots.len(),
        .roots.join(", ")
    )]
    UrdfTwoRoots {
        /// The root links, in file order.
        roots: Vec<String>,
    },
    /// A URDF joint has a type that URDF does not define.
    #[error(
        "URDF joint `{joint}`: unknown joint type `{kind}`; use revolute, continuous, prismatic or fixed"
    )]
    UrdfUnknownJointType {
        /// The joint.
        joint: String,
        /// The type as written.
        kind: String,
    },
    /// A numeric URDF attribute is not a finite number (or has the wrong number of entries).
    #[error(
        "URDF {element}: {attribute}=\"{text}\" is not {expected}; write finite decimal numbers such as 0.25 or 3.14159 (no units, no expressions)"
    )]
    UrdfBadNumber {
        /// The element, with its enclosing link or joint, e.g. ``joint `LJ1` <origin>``.
        element: String,
        /// The attribute.
        attribute: String,
        /// The value as written.
        text: String,
        /// What was expected (`3 numbers`, `a number`).
        expected: String,
    },
    /// A URDF joint kind (or feature) that the generator cannot represent.
    #[error("URDF joint `{joint}`: {kind} joints are not supported; {fix}")]
    UrdfUnsupportedJoint {
        /// The joint.
        joint: String,
        /// `floating`, `planar`, `spherical` or `mimic`.
        kind: String,
        /// How to fix the description.
        fix: String,
    },
    /// A URDF link's inertia is physically absurd for its mass (radius of gyration above the limit).
    #[error(
        "URDF link `{link}`: inertia is absurd for its mass {mass} kg: radius of gyration {radius:.3} m (largest principal moment {moment} kg·m² about the centre of mass) exceeds {limit} m; correct the <inertial>, list the link in UrdfOptions::drop_links, or set UrdfOptions::absurd_inertia to Drop"
    )]
    UrdfAbsurdInertia {
        /// The link.
        link: String,
        /// Its mass.
        mass: f64,
        /// The largest principal moment of inertia about the centre of mass.
        moment: f64,
        /// `sqrt(moment / mass)`.
        radius: f64,
        /// `UrdfOptions::max_radius_of_gyration`.
        limit: f64,
    },
    /// A URDF link's `<inertial>` is not physical: a negative mass, or an inertia about the
    /// centre of mass (`ixx` … `izz`) that is not positive semi-definite or breaks the triangle
    /// inequality by more than `UrdfOptions::inertia_tolerance` (no limit by default), or at
    /// all with `NonPhysicalInertia::Error`.
    #[error("URDF link `{link}` <inertial>: {detail}; {fix}")]
    UrdfNonPhysicalInertial {
        /// The link.
        link: String,
        /// What is wrong, with the numbers.
        detail: String,
        /// How to fix it.
        fix: String,
    },
    /// The model has no speed: every joint is fixed and there is no wheeled base, so there are
    /// no dynamics to generate.
    #[error(
        "the model has no moving joint (no speed): there are no dynamics to generate; give it a revolute, continuous or prismatic joint (URDF: type=\"fixed\" does not move), or a wheeled base"
    )]
    NoSpeeds,
    /// The mass matrix is singular: some speed moves no mass and no inertia.
    #[error(
        "the mass matrix is not positive definite: speed `{speed}` moves no mass or inertia that the speeds before it do not ({detail}); give the links it moves a mass or an inertia about its axis, or make its joint fixed"
    )]
    SingularMassMatrix {
        /// The first speed (in the order of u) whose pivot vanishes.
        speed: String,
        /// The pivot and the configuration.
        detail: String,
    },
    /// A URDF `<mimic>` joint whose constraint cannot be represented: its master joint is missing,
    /// fixed, dropped or part of the wheeled base, the mimic joints form a cycle, or the
    /// multiplier or offset is not a finite number.
    #[error("URDF joint `{joint}` <mimic>: {detail}")]
    UrdfBadMimic {
        /// The mimic joint.
        joint: String,
        /// What is wrong and how to fix it.
        detail: String,
    },
    /// A URDF import option (base declaration, dropped links, gravity) is inconsistent with the file.
    #[error("URDF import option `{option}`: {detail}")]
    UrdfBadOption {
        /// The option (`base.body_link`, `drop_links`, ...).
        option: String,
        /// What is wrong and how to fix it.
        detail: String,
    },
    /// A name that reaches generated code (coordinate, speed, parameter, model name) is not an
    /// identifier, is reserved by generated code, or clashes with another name there (see
    /// [`names`](crate::names)).
    #[error("{0}")]
    BadName(Box<BadName>),
    /// An operational frame (`[[frame]]`, a URDF tool frame, [`Model::add_frame`](crate::Model::add_frame))
    /// is malformed: an empty or taken name, an unknown parent, a rotation that is not proper or
    /// a translation that is not finite.
    #[error("operational frame `{frame}`: {detail}")]
    BadFrame {
        /// The frame's name.
        frame: String,
        /// What is wrong and how to fix it.
        detail: String,
    },
    /// Anything else about the base or gravity declarations.
    #[error("{item}: {detail}")]
    Invalid {
        /// The item.
        item: String,
        /// What is wrong and how to fix it.
        detail: String,
    },
}
