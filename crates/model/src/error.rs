//! Error type of the crate.

/// Everything that can go wrong when loading a model or calling a computation.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// The URDF file could not be read.
    #[error("cannot read URDF file `{path}`: {message}")]
    Io {
        /// Path of the file.
        path: String,
        /// Operating-system message.
        message: String,
    },
    /// The text is not a URDF that urdf-rs or the XML reader accepts.
    #[error("invalid URDF: {0}")]
    Urdf(String),
    /// Two `<link>` elements share a name.
    #[error("link `{link}` is declared more than once")]
    DuplicateLink {
        /// Link name.
        link: String,
    },
    /// Two `<joint>` elements share a name.
    #[error("joint `{joint}` is declared more than once")]
    DuplicateJoint {
        /// Joint name.
        joint: String,
    },
    /// A joint names a parent or child link that does not exist.
    #[error("joint `{joint}` refers to the missing link `{link}`")]
    MissingLink {
        /// Joint name.
        joint: String,
        /// The missing link.
        link: String,
    },
    /// A link is the child of two joints (the graph is not a tree).
    #[error("link `{link}` is the child of two joints, `{first}` and `{second}` (kinematic loop)")]
    MultipleParents {
        /// Link name.
        link: String,
        /// First joint.
        first: String,
        /// Second joint.
        second: String,
    },
    /// A closed chain of joints that is not connected to the root.
    #[error("kinematic loop through link `{link}`")]
    Loop {
        /// A link on the loop.
        link: String,
    },
    /// Every link is the child of some joint.
    #[error("the URDF has no root link (every link is the child of a joint)")]
    NoRoot,
    /// More than one link is never a child (the model is not connected).
    #[error("the URDF has several root links: {links:?}")]
    MultipleRoots {
        /// The root links.
        links: Vec<String>,
    },
    /// The URDF has no links at all.
    #[error("the URDF has no links")]
    Empty,
    /// Floating, planar or spherical joints are not supported.
    #[error("joint `{joint}` has unsupported type `{kind}` (supported: revolute, continuous, prismatic, fixed)")]
    UnsupportedJoint {
        /// Joint name.
        joint: String,
        /// The URDF type.
        kind: String,
    },
    /// A NaN or infinite number where a finite one is required.
    #[error("{element}: non-finite number in {field}")]
    NonFinite {
        /// `link `name`` or `joint `name``.
        element: String,
        /// Which attribute.
        field: String,
    },
    /// A link with negative mass.
    #[error("link `{link}` has negative mass {mass}")]
    NegativeMass {
        /// Link name.
        link: String,
        /// The mass in kg.
        mass: f64,
    },
    /// A link whose rotational inertia has a negative eigenvalue.
    #[error("link `{link}` has a rotational inertia with negative eigenvalue {eigenvalue}")]
    NegativeInertia {
        /// Link name.
        link: String,
        /// The most negative eigenvalue in kg·m².
        eigenvalue: f64,
    },
    /// A joint axis of zero length.
    #[error("joint `{joint}` has a zero-length axis")]
    ZeroAxis {
        /// Joint name.
        joint: String,
    },
    /// A mimic joint copies a joint that is not a movable joint of the model.
    #[error("joint `{joint}` mimics `{target}`, which is not a revolute, continuous or prismatic joint of the model")]
    MimicTarget {
        /// The mimic joint.
        joint: String,
        /// The joint it refers to.
        target: String,
    },
    /// A vector or matrix argument has the wrong size.
    #[error("{what}: expected size {expected_rows}x{expected_cols}, got {rows}x{cols}")]
    DimensionMismatch {
        /// Which argument.
        what: &'static str,
        /// Expected rows.
        expected_rows: usize,
        /// Expected columns.
        expected_cols: usize,
        /// Actual rows.
        rows: usize,
        /// Actual columns.
        cols: usize,
    },
    /// A NaN or infinity in an input (state, accelerations, torques, wrenches).
    #[error("non-finite value in {what}")]
    NonFiniteInput {
        /// Which argument.
        what: &'static str,
    },
    /// [`KinDyn::inverse_dynamics_after_ft_sensors`](crate::KinDyn::inverse_dynamics_after_ft_sensors)
    /// without a pass of [`KinDyn::ft_sensor_wrenches`](crate::KinDyn::ft_sensor_wrenches) free of external
    /// wrenches at the current state.
    #[error("no force/torque sensor pass without external wrenches at the current state to reuse")]
    NoSensorPass,
    /// A frame id that does not belong to this model.
    #[error("frame id {index} is out of range (the model has {count} frames)")]
    FrameOutOfRange {
        /// The index.
        index: usize,
        /// Number of frames of the model.
        count: usize,
    },
    /// A frame added to a loaded model names a missing parent, an existing name or a non-finite placement.
    #[error("frame `{name}` cannot be added: {reason}")]
    InvalidFrame {
        /// Name of the frame to add.
        name: String,
        /// What is wrong.
        reason: String,
    },
    /// An [`InertiaEdits`](crate::InertiaEdits) entry that cannot be applied (unknown link, non-positive or
    /// non-finite scale, non-finite CoM offset).
    #[error("{element}: invalid {field}: {reason}")]
    InvalidInertiaEdit {
        /// `inertia edits` or `inertia edit of link `name``.
        element: String,
        /// `mass_scale`, `com_offset` or `link`.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// An effort or velocity limit set on the model is not positive and finite, or names no joint of the
    /// model.
    #[error("joint {joint}: {what} limit {value} is not a positive finite number")]
    InvalidJointLimit {
        /// The joint (name, or index when out of range).
        joint: String,
        /// `effort` or `velocity`.
        what: &'static str,
        /// The rejected limit.
        value: f64,
    },
    /// A locked-joint entry that cannot be applied ([`crate::JointLock`]).
    #[error("locked joints: `{pattern}`: {reason}")]
    InvalidLock {
        /// The entry's joint name or glob.
        pattern: String,
        /// What is wrong.
        reason: String,
    },
    /// A force/torque sensor index that does not belong to this model.
    #[error("force/torque sensor index {index} is out of range (the model has {count} sensors)")]
    FtSensorOutOfRange {
        /// The index.
        index: usize,
        /// Number of force/torque sensors of the model.
        count: usize,
    },
    /// The articulated-body inertia seen by a joint (or the floating base) is singular: a subtree carries no
    /// mass or inertia that the joint can move.
    #[error("forward dynamics is singular at {what}: the subtree moved by it carries no inertia")]
    SingularInertia {
        /// `joint `name`` or `the floating base`.
        what: String,
    },
    /// Inertial parameters a model cannot hold (negative mass, or a first moment of mass without mass).
    #[error("inertial parameters of {what}: {reason}")]
    InvalidInertialParameters {
        /// `body `name`` or `the child side of force/torque sensor `name``.
        what: String,
        /// What is wrong.
        reason: String,
    },
    /// Two force/torque sensors lie in the same lumped body: the FT-split parameter layout of the
    /// regressors gives each host body one child-side part.
    #[error("force/torque sensors `{first}` and `{second}` both lie in body `{body}` (one sensor per lumped body is supported by the FT regressor)")]
    SharedFtSensorHost {
        /// The lumped body.
        body: String,
        /// First sensor.
        first: String,
        /// Second sensor.
        second: String,
    },
    /// A joint position outside the joint's URDF limits (user input: an initial posture, a standing state).
    #[error("joint `{joint}` at {value} is outside its limits [{lower}, {upper}]")]
    JointOutOfLimits {
        /// Joint name.
        joint: String,
        /// The position (rad or m).
        value: f64,
        /// Lower limit (rad or m).
        lower: f64,
        /// Upper limit (rad or m).
        upper: f64,
    },
}

/// Builds a [`ModelError::DimensionMismatch`] for a vector.
pub(crate) fn check_len(
    what: &'static str,
    expected: usize,
    actual: usize,
) -> Result<(), ModelError> {
    if expected == actual {
        Ok(())
    } else {
        Err(ModelError::DimensionMismatch {
            what,
            expected_rows: expected,
            expected_cols: 1,
            rows: actual,
            cols: 1,
        })
    }
}

/// Builds a [`ModelError::DimensionMismatch`] for a matrix.
pub(crate) fn check_shape(
    what: &'static str,
    expected: (usize, usize),
    actual: (usize, usize),
) -> Result<(), ModelError> {
    if expected == actual {
        Ok(())
    } else {
        Err(ModelError::DimensionMismatch {
            what,
            expected_rows: expected.0,
            expected_cols: expected.1,
            rows: actual.0,
            cols: actual.1,
        })
    }
}
