//! The URDF as MuJoCo is given it: MuJoCo's compiler options injected, the elements it does not need
//! removed, and `package://` mesh paths resolved.
//!
//! MuJoCo's URDF parser loads every mesh a `<visual>` or `<collision>` names, even those it then discards
//! (`discardvisual`) or that the plant excludes from collisions, and it knows no ROS packages: the official
//! iCub URDF (76 `package://iCub/meshes/...` paths) does not compile as it is. So, before MuJoCo reads it:
//!
//! * every `<visual>` is removed (MuJoCo would discard them: `discardvisual="true"`);
//! * every `<collision>` of a link that cannot touch the ground is removed (the plant lets only the sole
//!   bodies and the floor collide, so those geoms would be inert; iCub keeps only its two sole boxes);
//! * a kept mesh's `package://<package>/<path>` becomes `<ancestor>/<package>/<path>` for the nearest
//!   ancestor folder of the URDF that holds that file (the layout of an installed package share folder,
//!   e.g. `share/iCub/robots/iCubGazeboV2_7/model.urdf` and `share/iCub/meshes/...`).
//!
//! Every other element (links, joints, inertials, limits, dynamics) is passed through byte for byte.

use std::path::{Path, PathBuf};

use quick_xml::events::{BytesStart, Event};
use quick_xml::{Reader, Writer};

use crate::MujocoError;

/// Scheme of a ROS package resource path.
const PACKAGE_SCHEME: &str = "package://";

/// The compiler options injected into the URDF (`<mujoco><compiler .../></mujoco>`, the URDF extension
/// element of MuJoCo): visual geoms dropped, links without a joint fused into their parent (MuJoCo's URDF
/// default, made explicit; stride-model lumps them the same way, so bodies map one to one), relative mesh
/// paths looked up beside the URDF.
fn compiler_element(mesh_dir: &Path) -> String {
    format!(
        "<mujoco><compiler discardvisual=\"true\" fusestatic=\"true\" strippath=\"false\" \
         meshdir=\"{}\"/></mujoco>",
        mesh_dir.display()
    )
}

/// What [`prepare`] does to a URDF.
pub struct UrdfEdit<'a> {
    /// The URDF file (for errors, and the start of the `package://` search).
    pub path: &'a Path,
    /// The URDF links of the contact frames (the soles): each keeps the collision elements of the nearest
    /// link holding any, walking from it up its fixed joints.
    pub contact_links: &'a [String],
}

/// Counts of what [`prepare`] removed, for tests and documentation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UrdfStats {
    /// `<visual>` elements removed.
    pub visuals_removed: usize,
    /// `<collision>` elements removed.
    pub collisions_removed: usize,
    /// `<collision>` elements kept.
    pub collisions_kept: usize,
    /// `package://` paths resolved.
    pub packages_resolved: usize,
}

/// `urdf` (the text of `edit.path`) prepared for MuJoCo (see the module documentation).
///
/// # Errors
/// Malformed XML, no `<robot>` element, a `package://` path no ancestor folder holds.
pub fn prepare(urdf: &str, edit: &UrdfEdit<'_>) -> Result<(String, UrdfStats), MujocoError> {
    let xml_error = |message: String| MujocoError::UrdfXml {
        path: edit.path.to_path_buf(),
        message,
    };
    let dir = edit
        .path
        .parent()
        .map(|p| p.canonicalize().unwrap_or_else(|_| p.to_path_buf()))
        .unwrap_or_default();
    let kept = sole_collision_links(urdf, edit.contact_links).map_err(xml_error)?;
    let mut reader = Reader::from_str(urdf);
    let mut writer = Writer::new(Vec::with_capacity(urdf.len() + 256));
    let mut stats = UrdfStats::default();
    let mut link: Option<String> = None;
    let mut skip_depth = 0_usize;
    let mut robot_seen = false;
    loop {
        let event = reader
            .read_event()
            .map_err(|e| xml_error(format!("at byte {}: {e}", reader.error_position())))?;
        if skip_depth > 0 {
            match event {
                Event::Start(_) => skip_depth += 1,
                Event::End(_) => skip_depth -= 1,
                Event::Eof => return Err(xml_error("unclosed element".into())),
                _ => {}
            }
            continue;
        }
        let out = match event {
            Event::Eof => break,
            Event::Start(ref e) | Event::Empty(ref e) => {
                let open = matches!(event, Event::Start(_));
                match e.local_name().as_ref() {
                    b"link" => link = if open { Some(name_of(e)) } else { None },
                    b"visual" | b"collision" => {
                        let visual = e.local_name().as_ref() == b"visual";
                        let keep = !visual && link.as_ref().is_some_and(|l| kept.contains(l));
                        if !keep {
                            skip_depth = usize::from(open);
                            *if visual {
                                &mut stats.visuals_removed
                            } else {
                                &mut stats.collisions_removed
                            } += 1;
                            continue;
                        }
                        stats.collisions_kept += 1;
                    }
                    b"mesh" => {
                        let mesh = resolve_mesh(e, &dir, edit.path, &mut stats)?;
                        let ev = if open {
                            Event::Start(mesh)
                        } else {
                            Event::Empty(mesh)
                        };
                        write(&mut writer, ev, &xml_error)?;
                        continue;
                    }
                    b"robot" if !robot_seen => {
                        if !open {
                            return Err(xml_error("an empty <robot/> element".into()));
                        }
                        robot_seen = true;
                        write(&mut writer, event, &xml_error)?;
                        writer
                            .get_mut()
                            .extend_from_slice(compiler_element(&dir).as_bytes());
                        continue;
                    }
                    _ => {}
                }
                event
            }
            Event::End(ref e) if e.local_name().as_ref() == b"link" => {
                link = None;
                event
            }
            other => other,
        };
        write(&mut writer, out, &xml_error)?;
    }
    if !robot_seen {
        return Err(xml_error("no <robot> element".into()));
    }
    let text = String::from_utf8(writer.into_inner()).map_err(|e| xml_error(e.to_string()))?;
    Ok((text, stats))
}

/// For each link of `contact_links`, the nearest link holding `<collision>` elements among it and its
/// ancestors through fixed joints: the sole's own geometry. On iCub `l_sole` → `l_foot` (the sole box);
/// the foot shell mesh of `l_ankle_2`, one fixed joint further up and fused into the same MuJoCo body, is
/// not kept. A link without any such ancestor contributes nothing.
pub fn sole_collision_links(urdf: &str, contact_links: &[String]) -> Result<Vec<String>, String> {
    let mut fixed_parent: Vec<(String, String)> = Vec::new();
    let mut with_collision: Vec<String> = Vec::new();
    let mut reader = Reader::from_str(urdf);
    let (mut link, mut joint_fixed) = (None::<String>, false);
    loop {
        match reader
            .read_event()
            .map_err(|e| format!("at byte {}: {e}", reader.error_position()))?
        {
            Event::Eof => break,
            Event::Start(ref e) | Event::Empty(ref e) => match e.local_name().as_ref() {
                b"link" => link = Some(name_of(e)),
                b"collision" => with_collision.extend(link.clone()),
                b"joint" => {
                    link = None;
                    joint_fixed = attribute(e, b"type").as_deref() == Some("fixed");
                }
                b"parent" if joint_fixed => fixed_parent.push((String::new(), link_of(e))),
                b"child" if joint_fixed => {
                    if let Some(last) = fixed_parent.last_mut() {
                        last.0 = link_of(e);
                    }
                }
                _ => {}
            },
            Event::End(ref e) if e.local_name().as_ref() == b"joint" => joint_fixed = false,
            Event::End(ref e) if e.local_name().as_ref() == b"link" => link = None,
            _ => {}
        }
    }
    let mut kept = Vec::with_capacity(contact_links.len());
    for start in contact_links {
        let mut current = Some(start.clone());
        while let Some(l) = current {
            if with_collision.contains(&l) {
                kept.push(l);
                break;
            }
            current = fixed_parent
                .iter()
                .find(|(child, _)| *child == l)
                .map(|(_, parent)| parent.clone());
        }
    }
    Ok(kept)
}

/// The `link` attribute of a joint's `<parent>` / `<child>`.
fn link_of(e: &BytesStart<'_>) -> String {
    attribute(e, b"link").unwrap_or_default()
}

fn write(
    writer: &mut Writer<Vec<u8>>,
    event: Event<'_>,
    xml_error: &dyn Fn(String) -> MujocoError,
) -> Result<(), MujocoError> {
    writer
        .write_event(event)
        .map_err(|e| xml_error(e.to_string()))
}

/// The `name` attribute of an element (empty when absent or unreadable).
fn name_of(e: &BytesStart<'_>) -> String {
    attribute(e, b"name").unwrap_or_default()
}

/// An attribute's unescaped value.
fn attribute(e: &BytesStart<'_>, key: &[u8]) -> Option<String> {
    e.attributes()
        .flatten()
        .find(|a| a.key.as_ref() == key)
        .and_then(|a| a.unescape_value().ok().map(|v| v.into_owned()))
}

/// A `<mesh>` element with its `package://` filename resolved (other attributes unchanged).
fn resolve_mesh(
    e: &BytesStart<'_>,
    dir: &Path,
    urdf: &Path,
    stats: &mut UrdfStats,
) -> Result<BytesStart<'static>, MujocoError> {
    let mut mesh = BytesStart::new(String::from_utf8_lossy(e.name().as_ref()).into_owned());
    for a in e.attributes().flatten() {
        let value = a
            .unescape_value()
            .map(|v| v.into_owned())
            .unwrap_or_default();
        if a.key.as_ref() == b"filename" && value.starts_with(PACKAGE_SCHEME) {
            let file = resolve_package(&value, dir).ok_or_else(|| MujocoError::Package {
                path: urdf.to_path_buf(),
                uri: value.clone(),
            })?;
            stats.packages_resolved += 1;
            mesh.push_attribute(("filename", file.to_string_lossy().as_ref()));
        } else {
            let key = String::from_utf8_lossy(a.key.as_ref()).into_owned();
            mesh.push_attribute((key.as_str(), value.as_str()));
        }
    }
    Ok(mesh)
}

/// `package://<package>/<path>` as `<ancestor>/<package>/<path>` for the nearest ancestor of `dir`
/// (itself included) where that file exists.
pub fn resolve_package(uri: &str, dir: &Path) -> Option<PathBuf> {
    let relative = uri.strip_prefix(PACKAGE_SCHEME)?;
    if relative.is_empty() || relative.split('/').any(|c| c == "..") {
        return None;
    }
    dir.ancestors()
        .map(|a| a.join(relative))
        .find(|candidate| candidate.is_file())
}
