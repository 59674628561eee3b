//! A URDF link's geometry as bounding pieces ([`physid_core::spatial::bounding`]), for the paper's
//! "bounding ellipsoids from CAD geometry".
//!
//! - A link's `<collision>` shapes are used; if it has none, or one of them cannot be read, its
//!   `<visual>` shapes; if neither can be read the link contributes nothing and a warning says
//!   why.
//! - Primitives are exact: a box by its corners, a cylinder by its end discs, a capsule by its
//!   end balls, a sphere as a ball.
//! - Meshes (STL, COLLADA, OBJ; mesh-loader) by the vertices of their convex hull, scaled by the
//!   mesh's `scale`. `package://pkg/rel` is looked up as `<dir>/pkg/rel` (and `<dir>/rel` when
//!   `<dir>` itself is named `pkg`) for the URDF's folder and each folder above it, then for the
//!   folders of `ROS_PACKAGE_PATH` and [`GeometryOptions::package_dirs`]; `file://` and plain
//!   paths are absolute or relative to the URDF's folder.

use nalgebra::{Matrix3, Vector3};
use physid_core::spatial::bounding::{self, Piece};
use physid_core::spatial::{rpy_to_matrix, Ellipsoid};
use std::path::{Path, PathBuf};

/// How bounding ellipsoids are taken from a description's geometry.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GeometryOptions {
    /// Extra folders that hold ROS packages (searched after the URDF's own folders and
    /// `ROS_PACKAGE_PATH`).
    pub package_dirs: Vec<PathBuf>,
    /// Added to every semi-axis of an ellipsoid computed from geometry (m, ≥ 0).
    pub margin: f64,
    /// Do not compute ellipsoids from geometry at all.
    pub ignore_geometry: bool,
    /// Where computed ellipsoids are cached (by the content of the geometry they bound).
    pub cache: super::cache::CacheDir,
}

/// Where the URDF file lives and how to search for meshes.
pub(crate) struct Lookup<'a> {
    pub urdf: &'a Path,
    pub opts: &'a GeometryOptions,
}

/// The pieces of one link in its own frame: its collision shapes, else its visual ones.
/// `Err` explains why neither could be read.
pub(crate) fn link_pieces(
    link: &urdf_rs::Link,
    lookup: &Lookup,
) -> Result<Option<Vec<Piece>>, String> {
    let collision: Vec<(&urdf_rs::Pose, &urdf_rs::Geometry)> = link
        .collision
        .iter()
        .map(|c| (&c.origin, &c.geometry))
        .collect();
    let visual: Vec<(&urdf_rs::Pose, &urdf_rs::Geometry)> = link
        .visual
        .iter()
        .map(|v| (&v.origin, &v.geometry))
        .collect();
    let mut why = vec![];
    for (shapes, source) in [(collision, "collision"), (visual, "visual")] {
        if shapes.is_empty() {
            continue;
        }
        match shapes
            .iter()
            .map(|(origin, g)| shape_pieces(origin, g, lookup))
            .collect::<Result<Vec<_>, String>>()
        {
            Ok(pieces) => return Ok(Some(pieces.concat())),
            Err(e) => why.push(format!("{source}: {e}")),
        }
    }
    if why.is_empty() {
        Ok(None)
    } else {
        Err(why.join("; "))
    }
}

/// One `<geometry>` placed by its `<origin>`, in the link frame.
fn shape_pieces(
    origin: &urdf_rs::Pose,
    g: &urdf_rs::Geometry,
    lookup: &Lookup,
) -> Result<Vec<Piece>, String> {
    use urdf_rs::Geometry as G;
    let positive = |what: &str, v: f64| {
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(format!("{what} {v} is not a finite non-negative size"))
        }
    };
    let local = match g {
        G::Box { size } => {
            for v in size.0 {
                positive("box size", v)?;
            }
            bounding::box_corners(&Vector3::from(size.0))
        }
        G::Cylinder { radius, length } => bounding::cylinder_ends(
            positive("cylinder radius", *radius)?,
            positive("cylinder length", *length)?,
        ),
        G::Capsule { radius, length } => bounding::capsule_ends(
            positive("capsule radius", *radius)?,
            positive("capsule length", *length)?,
        ),
        G::Sphere { radius } => vec![Piece::Ball {
            center: Vector3::zeros(),
            radius: positive("sphere radius", *radius)?,
        }],
        G::Mesh { filename, scale } => {
            let path = resolve(filename, lookup)?;
            let s = scale.map_or(Vector3::repeat(1.0), |s| Vector3::from(s.0));
            mesh_pieces(&path, &s)?
        }
    };
    let rot = rpy_to_matrix(&Vector3::from(origin.rpy.0));
    let pos = Vector3::from(origin.xyz.0);
    Ok(local.iter().map(|p| p.moved(&rot, &pos)).collect())
}

/// The mesh files a URDF's text names that exist (`filename="…"` of every mesh, resolved as
/// [`resolve`] does with `package_dirs`): inputs an output must never replace.
pub fn referenced_meshes(urdf: &Path, package_dirs: &[PathBuf]) -> Vec<PathBuf> {
    let Ok(text) = std::fs::read_to_string(urdf) else {
        return vec![];
    };
    let opts = GeometryOptions {
        package_dirs: package_dirs.to_vec(),
        ..Default::default()
    };
    let lookup = Lookup { urdf, opts: &opts };
    let mut out = vec![];
    for quote in ['"', '\''] {
        let key = format!("filename={quote}");
        for (at, _) in text.match_indices(&key) {
            let rest = &text[at + key.len()..];
            if let Some(end) = rest.find(quote) {
                if let Ok(p) = resolve(&rest[..end], &lookup) {
                    out.push(p);
                }
            }
        }
    }
    out
}

/// The file a mesh `filename` names (see the module docs), or why it was not found.
fn resolve(filename: &str, lookup: &Lookup) -> Result<PathBuf, String> {
    // The URDF's real folder: a relative `--robot sub/arm.urdf` walks up past `sub` too (its
    // folders above were not searched, and the same file found its meshes only when named by
    // its absolute path).
    let real = std::fs::canonicalize(lookup.urdf).unwrap_or_else(|_| lookup.urdf.to_path_buf());
    let base = real.parent().unwrap_or(Path::new("."));
    let candidates: Vec<PathBuf> = if let Some(rest) = filename.strip_prefix("package://") {
        let (pkg, rel) = rest.split_once('/').unwrap_or((rest, ""));
        let ros = std::env::var_os("ROS_PACKAGE_PATH").unwrap_or_default();
        let roots = base
            .ancestors()
            .map(Path::to_path_buf)
            .chain(std::env::split_paths(&ros))
            .chain(lookup.opts.package_dirs.iter().cloned());
        roots
            .flat_map(|d| {
                let inside = (d.file_name().is_some_and(|n| n == pkg)).then(|| d.join(rel));
                [Some(d.join(pkg).join(rel)), inside]
            })
            .flatten()
            .collect()
    } else {
        let p = filename.strip_prefix("file://").unwrap_or(filename);
        vec![base.join(p)]
    };
    candidates
        .iter()
        .find(|p| p.is_file())
        .cloned()
        .ok_or_else(|| {
            format!("mesh '{filename}' not found (looked in the URDF's folder and those above it, ROS_PACKAGE_PATH and the given package folders)")
        })
}

/// The largest distance from a link frame a mesh vertex may lie at, and the largest scale (m).
const MAX_EXTENT: f64 = 1e3;

/// A binary STL's size must match its header's triangle count (`84 + 50 n` bytes); an ASCII
/// one (starting `solid` and not of that size) is left to the loader.
fn check_binary_stl(path: &Path) -> Result<(), String> {
    let is_stl = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("stl"));
    let Ok(meta) = std::fs::metadata(path) else {
        return Ok(());
    };
    if !is_stl || meta.len() < 84 {
        return Ok(());
    }
    let mut head = [0u8; 84];
    use std::io::Read;
    let read = std::fs::File::open(path).and_then(|mut f| f.read_exact(&mut head));
    if read.is_err() {
        return Ok(());
    }
    let n = u32::from_le_bytes([head[80], head[81], head[82], head[83]]) as u64;
    let expected = 84 + 50 * n;
    if expected == meta.len() || head.starts_with(b"solid") {
        return Ok(());
    }
    Err(format!(
        "{}: binary STL header claims {n} triangles ({expected} bytes) but the file has {} bytes",
        path.display(),
        meta.len()
    ))
}

/// A mesh file's vertices, scaled, reduced to its convex hull.
fn mesh_pieces(path: &Path, scale: &Vector3<f64>) -> Result<Vec<Piece>, String> {
    if !scale.iter().all(|s| s.is_finite() && s.abs() <= MAX_EXTENT) {
        return Err(format!(
            "{}: mesh scale {:?} is beyond ±{MAX_EXTENT} (a robot part is not larger than a kilometre)",
            path.display(),
            scale.as_slice()
        ));
    }
    check_binary_stl(path)?;
    let scene = mesh_loader::Loader::default()
        .load(path)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    let points: Vec<Vector3<f64>> = scene
        .meshes
        .iter()
        .flat_map(|m| m.vertices.iter())
        .map(|v| Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64).component_mul(scale))
        .collect();
    if points.is_empty() {
        return Err(format!("{}: the mesh has no vertices", path.display()));
    }
    if points.iter().any(|p| !p.iter().all(|x| x.is_finite())) {
        return Err(format!(
            "{}: the mesh has non-finite vertices",
            path.display()
        ));
    }
    if let Some((i, p)) = points
        .iter()
        .enumerate()
        .find(|(_, p)| p.amax() > MAX_EXTENT)
    {
        return Err(format!(
            "{}: vertex {i} (scaled) lies {:.3e} m from the link frame, beyond {MAX_EXTENT} m: a unit or scale error",
            path.display(),
            p.norm()
        ));
    }
    Ok(bounding::hull_vertices(&points)
        .into_iter()
        .map(Piece::Point)
        .collect())
}

/// The minimum-volume ellipsoid of `pieces`, grown by the margin, or why there is none; with a
/// warning when the cache held an entry for this geometry that cannot bound it (planted or
/// corrupted: ignored, solved again and replaced).
pub(crate) fn bound(
    pieces: &[Piece],
    opts: &GeometryOptions,
) -> Result<(Ellipsoid, Option<String>), String> {
    let key = super::cache::key(pieces);
    let cached = super::cache::get(&key, &opts.cache);
    let mut said = None;
    let e = match cached {
        Some(e) if bounding::could_bound(&e, pieces) => e,
        stale => {
            if stale.is_some() {
                let folder = opts
                    .cache
                    .folder()
                    .map_or("memory".into(), |f| f.display().to_string());
                said = Some(format!("the cached ellipsoid {key} (in {folder}) does not bound this geometry (a piece outside it, or larger than its box's): ignored, solved again and replaced"));
            }
            let e = bounding::minimum_volume_ellipsoid(pieces).map_err(|e| e.to_string())?;
            super::cache::put(&key, &e, &opts.cache);
            e
        }
    };
    Ok((bounding::with_margin(&e, opts.margin), said))
}

/// Pieces of a link moved into a body's frame by the link's pose in that frame.
pub(crate) fn into_frame(pieces: &[Piece], rot: &Matrix3<f64>, pos: &Vector3<f64>) -> Vec<Piece> {
    pieces.iter().map(|p| p.moved(rot, pos)).collect()
}

/// A URDF geometry as a shape (m), a mesh by the file it resolves to (`None` when it does not).
fn shape_kind(g: &urdf_rs::Geometry, lookup: &Lookup) -> Option<physid_core::model::ShapeKind> {
    use physid_core::model::ShapeKind;
    use urdf_rs::Geometry as G;
    Some(match g {
        G::Box { size } => ShapeKind::Box { size: size.0 },
        G::Cylinder { radius, length } => ShapeKind::Cylinder {
            radius: *radius,
            length: *length,
        },
        G::Capsule { radius, length } => ShapeKind::Capsule {
            radius: *radius,
            length: *length,
        },
        G::Sphere { radius } => ShapeKind::Sphere { radius: *radius },
        G::Mesh { filename, scale } => ShapeKind::Mesh {
            path: resolve(filename, lookup).ok()?,
            scale: scale.map_or([1.0; 3], |s| s.0),
        },
    })
}

/// A link's shapes for export, each placed in the link frame: its collision shapes, or its
/// visual ones when a collision mesh cannot be found (as [`link_pieces`] does); and the mesh
/// files of the chosen geometry that cannot be found (left out of every export).
pub(crate) fn link_shapes_and_missing(
    link: &urdf_rs::Link,
    lookup: &Lookup,
) -> (Vec<physid_core::model::Shape>, Vec<String>) {
    use physid_core::model::Shape;
    use urdf_rs::Geometry as G;
    let collision: Vec<_> = link
        .collision
        .iter()
        .map(|c| (&c.origin, &c.geometry))
        .collect();
    let visual: Vec<_> = link
        .visual
        .iter()
        .map(|v| (&v.origin, &v.geometry))
        .collect();
    let readable = |shapes: &[(&urdf_rs::Pose, &urdf_rs::Geometry)]| {
        !shapes.is_empty()
            && shapes.iter().all(|(_, g)| match g {
                G::Mesh { filename, .. } => resolve(filename, lookup).is_ok(),
                _ => true,
            })
    };
    // As for the bounds: the collision shapes if they can all be read, else the visual ones.
    let chosen = if readable(&collision) || !readable(&visual) {
        collision
    } else {
        visual
    };
    let missing: Vec<String> = chosen
        .iter()
        .filter_map(|(_, g)| match g {
            G::Mesh { filename, .. } if resolve(filename, lookup).is_err() => {
                Some(filename.clone())
            }
            _ => None,
        })
        .collect();
    let shapes = chosen
        .into_iter()
        .filter_map(|(origin, g)| {
            let kind = shape_kind(g, lookup)?;
            let pose = physid_core::spatial::Transform::from_pose(
                &rpy_to_matrix(&Vector3::from(origin.rpy.0)),
                &Vector3::from(origin.xyz.0),
            );
            Some(Shape { pose, kind })
        })
        .collect();
    (shapes, missing)
}
