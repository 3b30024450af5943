//! The URDF's standard elements read from the XML tree the loader has already parsed, into urdf-rs's types,
//! so that a file is parsed once (urdf-rs 0.10 parses it, writes it out again and parses that with a second
//! XML library). The result is the one `urdf_rs::read_from_string` gives for every file urdf-rs accepts
//! (test `urdf_element_reader.rs` on every URDF of the tests and of the model packages); the files it
//! rejects are rejected too, with this module's messages.
//!
//! URDF version rules (ROS URDF XML specification, versions 1.1 and 1.2): from 1.1 an `<origin>` may give
//! `quat_xyzw` instead of `rpy`; from 1.2 `<limit>` attributes left out mean "no limit", limits are checked
//! and shape dimensions must be positive.

use urdf_rs::{
    Axis, Calibration, Collision, Color, Dynamics, Geometry, Inertia, Inertial, Joint, JointLimit,
    JointType, Link, LinkName, Mass, Material, Mimic, Pose, Robot, SafetyController, Texture, Vec3,
    Vec4, Visual,
};

use crate::error::ModelError;

/// `(major, minor)` of `<robot version>`; 1.0 when absent or unreadable.
type Version = (u32, u32);

const V1_1: Version = (1, 1);
const V1_2: Version = (1, 2);

/// Reads the robot from the XML tree of a URDF file (`root` is the `<robot>` element).
pub(super) fn read_robot(root: &xml::Element) -> Result<Robot, ModelError> {
    let version = read_version(root.get_attribute("version", None));
    check_versioned(root, version)?;
    let mut robot = Robot {
        name: root.get_attribute("name", None).unwrap_or_default().into(),
        version: root.get_attribute("version", None).map(str::to_string),
        links: Vec::new(),
        joints: Vec::new(),
        materials: Vec::new(),
    };
    for child in elements(root) {
        match child.name.as_str() {
            "link" => robot.links.push(read_link(child, version)?),
            "joint" => robot.joints.push(read_joint(child, version)?),
            "material" => robot.materials.push(read_material(child)?),
            _ => {}
        }
    }
    Ok(robot)
}

fn read_version(text: Option<&str>) -> Version {
    text.and_then(|v| {
        let (major, minor) = v.trim().split_once('.')?;
        Some((major.parse().ok()?, minor.parse().ok()?))
    })
    .unwrap_or((1, 0))
}

/// The checks that depend on the version, on every element of the tree (urdf-rs applies them before it
/// reads anything): `quat_xyzw` beside `rpy`, the limits of a joint, the dimensions of a shape.
fn check_versioned(element: &xml::Element, version: Version) -> Result<(), ModelError> {
    let joint = (element.name == "joint").then(|| element.get_attribute("name", None));
    for child in elements(element) {
        match (joint, child.name.as_str()) {
            (_, "origin") => check_origin(child, version)?,
            (Some(name), "limit") => check_limit(child, name.unwrap_or_default(), version)?,
            _ if element.name == "geometry" && version >= V1_2 => check_shape(child)?,
            _ => {}
        }
        check_versioned(child, version)?;
    }
    Ok(())
}

/// The element children of `element`, in document order.
fn elements(element: &xml::Element) -> impl Iterator<Item = &xml::Element> {
    element.children.iter().filter_map(|c| match c {
        xml::Xml::ElementNode(e) => Some(e),
        _ => None,
    })
}

/// The only child named `name`, if any; two are an error (a field given twice).
fn single<'a>(
    element: &'a xml::Element,
    name: &str,
) -> Result<Option<&'a xml::Element>, ModelError> {
    let mut found = elements(element).filter(|c| c.name == name);
    let first = found.next();
    if found.next().is_some() {
        return Err(urdf_error(format!(
            "<{}>: duplicate field `{name}`",
            element.name
        )));
    }
    Ok(first)
}

fn required<'a>(element: &'a xml::Element, name: &str) -> Result<&'a xml::Element, ModelError> {
    single(element, name)?.ok_or_else(|| missing(element, name))
}

fn missing(element: &xml::Element, name: &str) -> ModelError {
    urdf_error(format!("<{}>: missing field `{name}`", element.name))
}

fn urdf_error(message: String) -> ModelError {
    ModelError::Urdf(message)
}

fn attribute<'a>(element: &'a xml::Element, name: &str) -> Result<&'a str, ModelError> {
    element
        .get_attribute(name, None)
        .ok_or_else(|| missing(element, name))
}

/// A number as urdf-rs reads one: surrounding white space ignored, `inf` and `nan` accepted.
fn number(element: &xml::Element, name: &str, text: &str) -> Result<f64, ModelError> {
    text.trim()
        .parse::<f64>()
        .map_err(|e| urdf_error(format!("<{}>: `{name}` = `{text}`: {e}", element.name)))
}

fn number_or(element: &xml::Element, name: &str, default: f64) -> Result<f64, ModelError> {
    element
        .get_attribute(name, None)
        .map_or(Ok(default), |t| number(element, name, t))
}

fn optional_number(element: &xml::Element, name: &str) -> Result<Option<f64>, ModelError> {
    element
        .get_attribute(name, None)
        .map(|t| number(element, name, t))
        .transpose()
}

/// `N` numbers separated by white space; tokens that are not numbers are skipped, as urdf-rs does.
fn numbers<const N: usize>(
    element: &xml::Element,
    name: &str,
    text: &str,
) -> Result<[f64; N], ModelError> {
    let mut out = [0.0; N];
    let mut count = 0;
    for value in text
        .split_whitespace()
        .filter_map(|t| t.parse::<f64>().ok())
    {
        if count < N {
            out[count] = value;
        }
        count += 1;
    }
    if count != N {
        return Err(urdf_error(format!(
            "<{}>: `{name}` = `{text}`: expected {N} numbers, found {count}",
            element.name
        )));
    }
    Ok(out)
}

fn vec3(element: &xml::Element, name: &str) -> Result<Vec3, ModelError> {
    numbers::<3>(element, name, attribute(element, name)?).map(Vec3)
}

fn vec3_or_zero(element: &xml::Element, name: &str) -> Result<Vec3, ModelError> {
    match element.get_attribute(name, None) {
        Some(text) => numbers::<3>(element, name, text).map(Vec3),
        None => Ok(Vec3::default()),
    }
}

/// `<origin xyz rpy>`, or `quat_xyzw` in place of `rpy` from version 1.1 (ignored before it).
fn read_pose(element: Option<&xml::Element>, version: Version) -> Result<Pose, ModelError> {
    let Some(element) = element else {
        return Ok(Pose::default());
    };
    let rpy = if version >= V1_1 && element.get_attribute("quat_xyzw", None).is_some() {
        Vec3(origin_quaternion(element)?)
    } else {
        vec3_or_zero(element, "rpy")?
    };
    Ok(Pose {
        xyz: vec3_or_zero(element, "xyz")?,
        rpy,
    })
}

/// The roll, pitch and yaw of an `<origin quat_xyzw>` (an error when `rpy` is given too).
fn origin_quaternion(element: &xml::Element) -> Result<[f64; 3], ModelError> {
    if element.get_attribute("rpy", None).is_some() {
        return Err(urdf_error(
            "<origin>: both `rpy` and `quat_xyzw` are given; use one".into(),
        ));
    }
    let text = attribute(element, "quat_xyzw")?;
    let values: Vec<f64> = text
        .split_whitespace()
        .map(str::parse::<f64>)
        .collect::<Result<_, _>>()
        .map_err(|_| quaternion_error(text))?;
    let quaternion: [f64; 4] = values.try_into().map_err(|_| quaternion_error(text))?;
    Ok(roll_pitch_yaw(quaternion))
}

fn quaternion_error(text: &str) -> ModelError {
    urdf_error(format!(
        "<origin>: `quat_xyzw` = `{text}` needs four numbers"
    ))
}

/// Roll, pitch, yaw of the quaternion `(x, y, z, w)` (normalised first; the identity for a zero one), the
/// conversion of urdfdom's `Rotation::getRPY`, with its gimbal-lock branches at |sin pitch| ≥ 0.99999.
fn roll_pitch_yaw(q: [f64; 4]) -> [f64; 3] {
    let norm = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let [x, y, z, w] = if norm > 0.0 {
        q.map(|v| v / norm)
    } else {
        [0.0, 0.0, 0.0, 1.0]
    };
    let half_pi = std::f64::consts::FRAC_PI_2;
    let sin_pitch = -2.0 * (x * z - w * y);
    if sin_pitch <= -0.99999 {
        return [0.0, -half_pi, 2.0 * x.atan2(-y)];
    }
    if sin_pitch >= 0.99999 {
        return [0.0, half_pi, 2.0 * (-x).atan2(y)];
    }
    let (xx, yy, zz, ww) = (x * x, y * y, z * z, w * w);
    [
        (2.0 * (y * z + w * x)).atan2(ww - xx - yy + zz),
        sin_pitch.asin(),
        (2.0 * (x * y + w * z)).atan2(ww + xx - yy - zz),
    ]
}

/// A limit attribute of version 1.2: a number, not NaN.
fn limit_value(limit: &xml::Element, name: &str, joint: &str) -> Result<Option<f64>, ModelError> {
    limit
        .get_attribute(name, None)
        .map(|t| match t.trim().parse::<f64>() {
            Ok(v) if !v.is_nan() => Ok(v),
            _ => Err(urdf_error(format!(
                "joint `{joint}`: <limit> `{name}` = `{t}` is not a number"
            ))),
        })
        .transpose()
}

/// From version 1.1, an `<origin quat_xyzw>` must be four numbers and come without `rpy`.
fn check_origin(origin: &xml::Element, version: Version) -> Result<(), ModelError> {
    if version >= V1_1 && origin.get_attribute("quat_xyzw", None).is_some() {
        origin_quaternion(origin)?;
    }
    Ok(())
}

/// Version 1.2's checks of a `<limit>` (none before): `lower ≤ upper`, no negative effort, velocity,
/// acceleration, deceleration or jerk.
fn check_limit(limit: &xml::Element, joint: &str, version: Version) -> Result<(), ModelError> {
    if version < V1_2 {
        return Ok(());
    }
    let lower = limit_value(limit, "lower", joint)?;
    let upper = limit_value(limit, "upper", joint)?;
    if let (Some(lower), Some(upper)) = (lower, upper) {
        if upper < lower {
            return Err(urdf_error(format!(
                "joint `{joint}`: <limit> upper ({upper}) below lower ({lower})"
            )));
        }
    }
    for name in ["effort", "velocity", "acceleration", "deceleration", "jerk"] {
        if let Some(value) = limit_value(limit, name, joint)? {
            if value < 0.0 {
                return Err(urdf_error(format!(
                    "joint `{joint}`: <limit> `{name}` ({value}) is negative"
                )));
            }
        }
    }
    Ok(())
}

/// Version 1.2's check of a shape: every dimension positive and finite.
fn check_shape(shape: &xml::Element) -> Result<(), ModelError> {
    let dimensions: &[&str] = match shape.name.as_str() {
        "sphere" => &["radius"],
        "box" => &["size"],
        "cylinder" | "capsule" => &["radius", "length"],
        _ => return Ok(()),
    };
    for name in dimensions {
        if let Some(text) = shape.get_attribute(name, None) {
            let valid = text
                .split_whitespace()
                .filter_map(|t| t.parse::<f64>().ok())
                .all(|v| v.is_finite() && v > 0.0);
            if !valid {
                return Err(urdf_error(format!(
                    "<{}>: `{name}` = `{text}` must be positive and finite",
                    shape.name
                )));
            }
        }
    }
    Ok(())
}

fn read_link(element: &xml::Element, version: Version) -> Result<Link, ModelError> {
    let inertial = match single(element, "inertial")? {
        Some(i) => Inertial {
            origin: read_pose(single(i, "origin")?, version)?,
            mass: Mass {
                value: number(i, "value", attribute(required(i, "mass")?, "value")?)?,
            },
            inertia: read_inertia(required(i, "inertia")?)?,
        },
        None => Inertial::default(),
    };
    let mut link = Link {
        name: attribute(element, "name")?.into(),
        inertial,
        visual: Vec::new(),
        collision: Vec::new(),
    };
    for child in elements(element) {
        match child.name.as_str() {
            "visual" => link.visual.push(Visual {
                name: child.get_attribute("name", None).map(str::to_string),
                origin: read_pose(single(child, "origin")?, version)?,
                geometry: read_geometry(required(child, "geometry")?)?,
                material: single(child, "material")?.map(read_material).transpose()?,
            }),
            "collision" => link.collision.push(Collision {
                name: child.get_attribute("name", None).map(str::to_string),
                origin: read_pose(single(child, "origin")?, version)?,
                geometry: read_geometry(required(child, "geometry")?)?,
            }),
            _ => {}
        }
    }
    Ok(link)
}

fn read_inertia(element: &xml::Element) -> Result<Inertia, ModelError> {
    let get = |name: &str| number(element, name, attribute(element, name)?);
    Ok(Inertia {
        ixx: get("ixx")?,
        ixy: get("ixy")?,
        ixz: get("ixz")?,
        iyy: get("iyy")?,
        iyz: get("iyz")?,
        izz: get("izz")?,
    })
}

/// `<geometry>`: its first element child names the shape.
fn read_geometry(element: &xml::Element) -> Result<Geometry, ModelError> {
    let shape = elements(element)
        .next()
        .ok_or_else(|| urdf_error("<geometry> without a shape".into()))?;
    let get = |name: &str| number(shape, name, attribute(shape, name)?);
    Ok(match shape.name.as_str() {
        "box" => Geometry::Box {
            size: vec3(shape, "size")?,
        },
        "cylinder" => Geometry::Cylinder {
            radius: get("radius")?,
            length: get("length")?,
        },
        "capsule" => Geometry::Capsule {
            radius: get("radius")?,
            length: get("length")?,
        },
        "sphere" => Geometry::Sphere {
            radius: get("radius")?,
        },
        "mesh" => Geometry::Mesh {
            filename: attribute(shape, "filename")?.into(),
            scale: shape
                .get_attribute("scale", None)
                .map(|t| numbers::<3>(shape, "scale", t).map(Vec3))
                .transpose()?,
        },
        other => return Err(urdf_error(format!("<geometry>: unknown shape <{other}>"))),
    })
}

fn read_material(element: &xml::Element) -> Result<Material, ModelError> {
    Ok(Material {
        name: attribute(element, "name")?.into(),
        color: single(element, "color")?
            .map(|c| {
                numbers::<4>(c, "rgba", attribute(c, "rgba")?).map(|v| Color { rgba: Vec4(v) })
            })
            .transpose()?,
        texture: single(element, "texture")?
            .map(|t| attribute(t, "filename").map(|f| Texture { filename: f.into() }))
            .transpose()?,
    })
}

fn read_joint(element: &xml::Element, version: Version) -> Result<Joint, ModelError> {
    let link = |name: &str| -> Result<LinkName, ModelError> {
        Ok(LinkName {
            link: attribute(required(element, name)?, "link")?.into(),
        })
    };
    Ok(Joint {
        name: attribute(element, "name")?.into(),
        joint_type: joint_type(element, attribute(element, "type")?)?,
        origin: read_pose(single(element, "origin")?, version)?,
        parent: link("parent")?,
        child: link("child")?,
        axis: match single(element, "axis")? {
            Some(a) => Axis {
                xyz: vec3(a, "xyz")?,
            },
            None => Axis::default(),
        },
        limit: match single(element, "limit")? {
            Some(l) => read_limit(l, version)?,
            None => JointLimit::default(),
        },
        calibration: single(element, "calibration")?
            .map(|c| -> Result<_, ModelError> {
                Ok(Calibration {
                    rising: optional_number(c, "rising")?,
                    falling: optional_number(c, "falling")?,
                })
            })
            .transpose()?,
        dynamics: single(element, "dynamics")?
            .map(|d| -> Result<_, ModelError> {
                Ok(Dynamics {
                    damping: number_or(d, "damping", 0.0)?,
                    friction: number_or(d, "friction", 0.0)?,
                })
            })
            .transpose()?,
        mimic: single(element, "mimic")?
            .map(|m| -> Result<_, ModelError> {
                Ok(Mimic {
                    joint: attribute(m, "joint")?.into(),
                    multiplier: optional_number(m, "multiplier")?,
                    offset: optional_number(m, "offset")?,
                })
            })
            .transpose()?,
        safety_controller: single(element, "safety_controller")?
            .map(|s| -> Result<_, ModelError> {
                Ok(SafetyController {
                    soft_lower_limit: number_or(s, "soft_lower_limit", 0.0)?,
                    soft_upper_limit: number_or(s, "soft_upper_limit", 0.0)?,
                    k_position: number_or(s, "k_position", 0.0)?,
                    k_velocity: number(s, "k_velocity", attribute(s, "k_velocity")?)?,
                })
            })
            .transpose()?,
    })
}

fn joint_type(element: &xml::Element, text: &str) -> Result<JointType, ModelError> {
    Ok(match text {
        "revolute" => JointType::Revolute,
        "continuous" => JointType::Continuous,
        "prismatic" => JointType::Prismatic,
        "fixed" => JointType::Fixed,
        "floating" => JointType::Floating,
        "planar" => JointType::Planar,
        "spherical" => JointType::Spherical,
        other => {
            return Err(urdf_error(format!(
                "<{}>: unknown joint type `{other}`",
                element.name
            )))
        }
    })
}

/// `<limit>`: before version 1.2 `velocity` is required, the other bounds default to 0 and acceleration,
/// deceleration and jerk are ignored (unbounded); from 1.2 a missing bound is unbounded and `deceleration`
/// defaults to `acceleration`.
fn read_limit(limit: &xml::Element, version: Version) -> Result<JointLimit, ModelError> {
    if version < V1_2 {
        return Ok(JointLimit {
            lower: number_or(limit, "lower", 0.0)?,
            upper: number_or(limit, "upper", 0.0)?,
            effort: number_or(limit, "effort", 0.0)?,
            velocity: number(limit, "velocity", attribute(limit, "velocity")?)?,
            ..JointLimit::default()
        });
    }
    let acceleration = number_or(limit, "acceleration", f64::INFINITY)?;
    Ok(JointLimit {
        lower: number_or(limit, "lower", f64::NEG_INFINITY)?,
        upper: number_or(limit, "upper", f64::INFINITY)?,
        effort: number_or(limit, "effort", f64::INFINITY)?,
        velocity: number_or(limit, "velocity", f64::INFINITY)?,
        acceleration,
        deceleration: number_or(limit, "deceleration", acceleration)?,
        jerk: number_or(limit, "jerk", f64::INFINITY)?,
    })
}

#[cfg(test)]
#[path = "element_tests.rs"]
mod tests;
