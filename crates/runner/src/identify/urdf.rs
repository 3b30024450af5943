//! The identified URDF: the prior URDF text with the `<inertial>` of every link of the model replaced, so
//! that the URDF loads to a model with the identified parameters (and keeps everything else: joints,
//! sensors, visuals, extensions).
//!
//! A model body lumps the links attached through fixed joints, and a force/torque sensor splits its host
//! body in two (FT-split layout, `stride_model::inertial`): the host part is written to the body's own
//! link, each sensor's child-side part to the sensor joint's child link, and the other lumped links get
//! zero mass (their inertia is in the first two).

use nalgebra::{DVector, Matrix3, Vector3};
use stride_model::inertial::{mass_com_inertia, transform_parameters, vech, InertialParameters};
use stride_model::{FrameKind, Model};

use super::report::block;
use super::IdentifyError;

/// The prior URDF `urdf` with the inertial parameters `split` (FT-split layout of `model`, the model
/// loaded from `urdf`) written into its links.
///
/// # Errors
/// [`IdentifyError::Content`] when a link of the model is not found in the text or `split` has the wrong
/// length.
pub fn identified_urdf(
    urdf: &str,
    model: &Model,
    split: &DVector<f64>,
) -> Result<String, IdentifyError> {
    let (nb, ns) = (model.body_count(), model.ft_sensors().len());
    if split.len() != 10 * (nb + ns) {
        return Err(IdentifyError::Content(format!(
            "{} inertial parameters for a model of {nb} bodies and {ns} force/torque sensors",
            split.len()
        )));
    }
    let mut out = urdf.to_string();
    for frame in model.frames() {
        if !matches!(frame.kind, FrameKind::Body | FrameKind::MergedLink) {
            continue;
        }
        let own = if frame.kind == FrameKind::Body {
            Some(block(split, frame.link))
        } else {
            model
                .ft_sensors()
                .iter()
                .position(|s| s.child_link == frame.name)
                .map(|k| block(split, nb + k))
        };
        let in_link = match own {
            Some(pi) => {
                let inv = frame.placement.inverse();
                transform_parameters(
                    &pi,
                    inv.rotation.to_rotation_matrix().matrix(),
                    &inv.translation.vector,
                )
            }
            None => InertialParameters::zeros(),
        };
        out = replace_inertial(&out, &frame.name, &inertial_element(&in_link))?;
    }
    Ok(out)
}

/// `<inertial>` of `π` (about the CoM, link axes; zero mass for a zero π).
fn inertial_element(pi: &InertialParameters) -> String {
    let (m, c, i): (f64, Vector3<f64>, Matrix3<f64>) = if pi[0] > 0.0 {
        mass_com_inertia(pi)
    } else {
        (0.0, Vector3::zeros(), Matrix3::zeros())
    };
    let [ixx, ixy, ixz, iyy, iyz, izz] = vech(&i);
    format!(
        "<inertial>\n      <origin xyz=\"{:?} {:?} {:?}\" rpy=\"0 0 0\"/>\n      <mass value=\"{m:?}\"/>\n      \
         <inertia ixx=\"{ixx:?}\" ixy=\"{ixy:?}\" ixz=\"{ixz:?}\" iyy=\"{iyy:?}\" iyz=\"{iyz:?}\" izz=\"{izz:?}\"/>\n    </inertial>",
        c.x, c.y, c.z,
    )
}

fn replace_inertial(text: &str, name: &str, inertial: &str) -> Result<String, IdentifyError> {
    let missing = || IdentifyError::Content(format!("link `{name}` not found in the URDF text"));
    let start = [format!("<link name=\"{name}\""), format!("<link name='{name}'")]
        .iter()
        .find_map(|p| {
            text.match_indices(p.as_str())
                .map(|(i, _)| i)
                .find(|&i| matches!(text[i + p.len()..].chars().next(), Some(c) if c == '>' || c == '/' || c.is_whitespace()))
        })
        .ok_or_else(missing)?;
    let open_end = start + text[start..].find('>').ok_or_else(missing)?;
    if text[..open_end].ends_with('/') {
        let head = &text[..open_end - 1];
        return Ok(format!(
            "{head}>\n    {inertial}\n  </link>{}",
            &text[open_end + 1..]
        ));
    }
    let close = open_end + text[open_end..].find("</link>").ok_or_else(missing)?;
    let body = &text[open_end + 1..close];
    let new_body = match (body.find("<inertial"), body.find("</inertial>")) {
        (Some(a), Some(b)) => format!(
            "{}{inertial}{}",
            &body[..a],
            &body[b + "</inertial>".len()..]
        ),
        _ => format!("\n    {inertial}{body}"),
    };
    Ok(format!(
        "{}{new_body}{}",
        &text[..open_end + 1],
        &text[close..]
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The identified URDF of the bundled model with its own parameters loads to the same dynamics (every
    /// body's lumped π and every sensor's child side), and with changed parameters to those parameters.
    #[test]
    fn written_urdf_loads_to_the_written_parameters() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../models/stride_humanoid.urdf"
        );
        let urdf = std::fs::read_to_string(path).unwrap();
        let model = Model::from_urdf_str(&urdf).unwrap();
        let mut split = model.ft_split_inertial_parameters().unwrap();
        for (k, v) in split.iter_mut().enumerate() {
            if k % 10 == 0 {
                *v *= 1.0 + 0.01 * (k / 10) as f64;
            }
        }
        let text = identified_urdf(&urdf, &model, &split).unwrap();
        let back = Model::from_urdf_str(&text).unwrap();
        let got = back.ft_split_inertial_parameters().unwrap();
        let err = (&got - &split).amax();
        assert!(err < 1e-12 * split.amax(), "max difference {err:e}");
        assert_eq!(back.ft_sensors().len(), model.ft_sensors().len());
        assert_eq!(back.dof(), model.dof());
    }

    #[test]
    fn self_closing_and_missing_links() {
        let text =
            "<robot name=\"r\">\n  <link name=\"a\"/>\n  <link name=\"ab\">\n  </link>\n</robot>";
        let out = replace_inertial(text, "a", "<inertial/>").unwrap();
        assert!(out.contains("<link name=\"a\">\n    <inertial/>\n  </link>"));
        assert!(out.contains("<link name=\"ab\">\n  </link>"));
        assert!(replace_inertial(text, "b", "<inertial/>").is_err());
    }
}
