//! Triangle meshes of URDF geometry: STL (binary and ASCII) and Wavefront OBJ files, and boxes.
//! COLLADA (`.dae`) is not read: a foot described only by a DAE mesh is reported as unsupported.

use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Point3, Vector3};

/// A triangle, three vertices \[m\].
pub type Triangle = [Point3<f64>; 3];

/// Why a mesh could not be read.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be read.
    #[error("cannot read mesh {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A format this reader does not handle.
    #[error("mesh {}: unsupported format (supported: .stl binary and ASCII, .obj)", path.display())]
    Unsupported {
        /// The file.
        path: PathBuf,
    },
    /// The file is not valid in its format.
    #[error("mesh {}: {message}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A `package://` path whose package folder was not found.
    #[error("mesh `{uri}`: package `{package}` not found above the URDF's folder nor in ROS_PACKAGE_PATH")]
    Package {
        /// The URI as written.
        uri: String,
        /// The package name.
        package: String,
    },
}

/// The triangles of the box of edge lengths `size` centred at the origin (12 triangles, outward
/// normals by the right-hand rule).
pub fn box_triangles(size: [f64; 3]) -> Vec<Triangle> {
    let h = Vector3::from(size) * 0.5;
    let corner = |i: usize| {
        Point3::new(
            if i & 1 == 0 { -h.x } else { h.x },
            if i & 2 == 0 { -h.y } else { h.y },
            if i & 4 == 0 { -h.z } else { h.z },
        )
    };
    // Faces as corner quadruples, counter-clockwise seen from outside.
    const FACES: [[usize; 4]; 6] = [
        [0, 2, 3, 1], // z−
        [4, 5, 7, 6], // z+
        [0, 1, 5, 4], // y−
        [2, 6, 7, 3], // y+
        [0, 4, 6, 2], // x−
        [1, 3, 7, 5], // x+
    ];
    FACES
        .iter()
        .flat_map(|f| {
            [
                [corner(f[0]), corner(f[1]), corner(f[2])],
                [corner(f[0]), corner(f[2]), corner(f[3])],
            ]
        })
        .collect()
}

/// Reads the triangles of an STL or OBJ file, scaled by `scale`.
pub fn read_mesh(path: &Path, scale: [f64; 3]) -> Result<Vec<Triangle>, MeshError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let bytes = std::fs::read(path).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let invalid = |message: String| MeshError::Invalid {
        path: path.to_path_buf(),
        message,
    };
    let mut tris = match ext.as_str() {
        "stl" => read_stl(&bytes).map_err(invalid)?,
        "obj" => read_obj(&String::from_utf8_lossy(&bytes)).map_err(invalid)?,
        _ => {
            return Err(MeshError::Unsupported {
                path: path.to_path_buf(),
            })
        }
    };
    // A mirroring scale (negative determinant) turns the faces inside out: swap two vertices back.
    let mirrored = scale[0] * scale[1] * scale[2] < 0.0;
    for t in &mut tris {
        for p in t.iter_mut() {
            p.coords.component_mul_assign(&Vector3::from(scale));
        }
        if mirrored {
            t.swap(1, 2);
        }
    }
    Ok(tris)
}

/// Binary STL: 80-byte header, u32 count, 50 bytes per triangle; ASCII STL: `vertex x y z` lines.
fn read_stl(bytes: &[u8]) -> Result<Vec<Triangle>, String> {
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if bytes.len() == 84 + 50 * n {
            let f = |o: usize| {
                f64::from(f32::from_le_bytes([
                    bytes[o],
                    bytes[o + 1],
                    bytes[o + 2],
                    bytes[o + 3],
                ]))
            };
            let p = |o: usize| Point3::new(f(o), f(o + 4), f(o + 8));
            return Ok((0..n)
                .map(|i| {
                    let o = 84 + 50 * i + 12;
                    [p(o), p(o + 12), p(o + 24)]
                })
                .collect());
        }
    }
    let text = String::from_utf8_lossy(bytes);
    let vertices = text
        .lines()
        .filter_map(|l| l.trim().strip_prefix("vertex"))
        .map(parse_point)
        .collect::<Result<Vec<_>, _>>()?;
    if vertices.is_empty() || vertices.len() % 3 != 0 {
        return Err(
            "neither a binary STL (size does not match the triangle count) nor an ASCII STL".into(),
        );
    }
    Ok(vertices.chunks(3).map(|c| [c[0], c[1], c[2]]).collect())
}

/// OBJ: `v x y z` vertices and `f a b c ...` faces (1-based or negative indices, `a/t/n` forms; polygons
/// fanned into triangles).
fn read_obj(text: &str) -> Result<Vec<Triangle>, String> {
    let mut vertices = Vec::new();
    let mut tris = Vec::new();
    for line in text.lines() {
        let line = line.trim();
        if let Some(rest) = line.strip_prefix("v ") {
            vertices.push(parse_point(rest)?);
        } else if let Some(rest) = line.strip_prefix("f ") {
            let idx = rest
                .split_whitespace()
                .map(|t| obj_index(t, vertices.len()))
                .collect::<Result<Vec<_>, _>>()?;
            for k in 1..idx.len().saturating_sub(1) {
                tris.push([vertices[idx[0]], vertices[idx[k]], vertices[idx[k + 1]]]);
            }
        }
    }
    Ok(tris)
}

fn obj_index(token: &str, count: usize) -> Result<usize, String> {
    let first = token.split('/').next().unwrap_or_default();
    let i: i64 = first
        .parse()
        .map_err(|_| format!("bad face index `{token}`"))?;
    let resolved = if i < 0 { count as i64 + i } else { i - 1 };
    if resolved < 0 || resolved as usize >= count {
        return Err(format!("face index `{token}` out of range"));
    }
    Ok(resolved as usize)
}

fn parse_point(text: &str) -> Result<Point3<f64>, String> {
    let v = text
        .split_whitespace()
        .take(3)
        .map(|t| t.parse::<f64>().map_err(|_| format!("bad number `{t}`")))
        .collect::<Result<Vec<_>, _>>()?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Point3::new(*x, *y, *z)),
        _ => Err(format!("expected three finite coordinates in `{text}`")),
    }
}

/// The file a URDF mesh `filename` names: `package://pkg/rest` is looked up as a folder `pkg` above the
/// URDF's folder (or in `ROS_PACKAGE_PATH`), `file://` is stripped, a relative path is relative to the
/// URDF's folder.
pub fn resolve_mesh_path(uri: &str, urdf_dir: &Path) -> Result<PathBuf, MeshError> {
    if let Some(rest) = uri.strip_prefix("package://") {
        let (package, rel) = rest.split_once('/').unwrap_or((rest, ""));
        let mut roots: Vec<PathBuf> = urdf_dir.ancestors().map(Path::to_path_buf).collect();
        if let Ok(paths) = std::env::var("ROS_PACKAGE_PATH") {
            roots.extend(std::env::split_paths(&paths));
        }
        for root in roots {
            if root.file_name().is_some_and(|n| n == package) {
                return Ok(root.join(rel));
            }
            let candidate = root.join(package);
            if candidate.join(rel).exists() {
                return Ok(candidate.join(rel));
            }
        }
        return Err(MeshError::Package {
            uri: uri.to_string(),
            package: package.to_string(),
        });
    }
    let path = PathBuf::from(uri.strip_prefix("file://").unwrap_or(uri));
    Ok(if path.is_absolute() {
        path
    } else {
        urdf_dir.join(path)
    })
}

/// `triangles` moved by `pose`.
pub fn transformed(triangles: &[Triangle], pose: &Isometry3<f64>) -> Vec<Triangle> {
    triangles
        .iter()
        .map(|t| [pose * t[0], pose * t[1], pose * t[2]])
        .collect()
}

/// The triangles of a cylinder of `radius` and `length` along z, centred at the origin, its caps as
/// `segments`-gons (outward normals).
pub fn cylinder_triangles(radius: f64, length: f64, segments: usize) -> Vec<Triangle> {
    let h = 0.5 * length;
    let at = |k: usize, z: f64| {
        let a = std::f64::consts::TAU * k as f64 / segments as f64;
        Point3::new(radius * a.cos(), radius * a.sin(), z)
    };
    let (bottom, top) = (Point3::new(0.0, 0.0, -h), Point3::new(0.0, 0.0, h));
    (0..segments)
        .flat_map(|k| {
            let j = (k + 1) % segments;
            [
                [bottom, at(j, -h), at(k, -h)],
                [top, at(k, h), at(j, h)],
                [at(k, -h), at(j, -h), at(j, h)],
                [at(k, -h), at(j, h), at(k, h)],
            ]
        })
        .collect()
}
