//! Triangle-mesh animations (seed 000 §6.1: "we begin with a sequence of triangle meshes
//! animating changes to the boundary conditions, such as the flapping wings of a bird"): one
//! fixed triangle list, vertex positions per frame, and the closed parts (OBJ objects) the
//! surface is made of. Read from and written to OBJ sequences (one file per frame, every
//! file with the same objects, vertices and faces).

use std::ops::Range;
use std::path::{Path, PathBuf};

use super::sdf::{ObjSurface, Sdf, Union};
use super::MeshError;

/// A triangle-mesh animation of fixed topology made of closed parts.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceAnimation {
    /// Corner vertex indices of every triangle (all parts).
    pub triangles: Vec<[u32; 3]>,
    /// Per part: its name and its range of triangles. Parts may overlap (the surface is
    /// their union); each must be closed.
    pub parts: Vec<(String, Range<usize>)>,
    /// Per frame, the position of every vertex.
    pub frames: Vec<Vec<[f64; 3]>>,
}

fn file_error(path: &Path, message: impl std::fmt::Display) -> MeshError {
    MeshError::Generation(format!("{}: {message}", path.display()))
}

impl SurfaceAnimation {
    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.frames.len()
    }

    /// The corners of triangle `t` at `frame`.
    pub fn triangle_at(&self, frame: usize, t: usize) -> [[f64; 3]; 3] {
        self.triangles[t].map(|v| self.frames[frame][v as usize])
    }

    /// The signed distance to the surface at `frame`: the union of its parts, each the
    /// signed distance to a closed triangle surface ([`ObjSurface`]).
    pub fn sdf(&self, frame: usize) -> Result<Union, MeshError> {
        let mut parts: Vec<Box<dyn Sdf>> = Vec::new();
        for (name, range) in &self.parts {
            let triangles = range.clone().map(|t| self.triangle_at(frame, t)).collect();
            let surface = ObjSurface::from_triangles(triangles)
                .map_err(|e| MeshError::Generation(format!("part {name}: {e}")))?;
            parts.push(Box::new(surface));
        }
        Ok(Union(parts))
    }

    /// Writes `frame` as an OBJ file, one object per part (17 significant digits, so the
    /// positions read back exactly).
    pub fn write_obj(&self, frame: usize, path: &Path) -> Result<(), MeshError> {
        use std::fmt::Write as _;
        let mut s = String::from("# galerkin surface animation frame\n");
        let positions = &self.frames[frame];
        let mut written = 0u32;
        for (name, range) in &self.parts {
            // Each object lists its own vertices (OBJ indices are global and 1-based).
            let mut local: Vec<u32> = range.clone().flat_map(|t| self.triangles[t]).collect();
            local.sort_unstable();
            local.dedup();
            let first = written;
            written += local.len() as u32;
            let _ = writeln!(s, "o {name}");
            for &v in &local {
                let p = positions[v as usize];
                let _ = writeln!(s, "v {:.17e} {:.17e} {:.17e}", p[0], p[1], p[2]);
            }
            for t in range.clone() {
                let [a, b, c] =
                    self.triangles[t].map(|v| first + 1 + local.binary_search(&v).unwrap_or_default() as u32);
                let _ = writeln!(s, "f {a} {b} {c}");
            }
        }
        std::fs::write(path, s).map_err(|e| file_error(path, e))
    }

    /// Writes every frame to `dir/{stem}_{frame:04}.obj` (the directory is created).
    pub fn write_sequence(&self, dir: &Path, stem: &str) -> Result<Vec<PathBuf>, MeshError> {
        std::fs::create_dir_all(dir).map_err(|e| file_error(dir, e))?;
        (0..self.frame_count())
            .map(|k| {
                let path = dir.join(format!("{stem}_{k:04}.obj"));
                self.write_obj(k, &path).map(|()| path)
            })
            .collect()
    }

    /// Reads an OBJ sequence, one file per frame in the order given. Every file must have
    /// the objects, vertex counts and faces of the first; errors name the file and what
    /// differs.
    pub fn read_sequence(files: &[PathBuf]) -> Result<Self, MeshError> {
        let Some(first) = files.first() else {
            return Err(MeshError::Generation("an OBJ sequence needs at least one file".into()));
        };
        let (triangles, parts, positions) = read_obj(first)?;
        let mut frames = vec![positions];
        for path in &files[1..] {
            let (t, p, positions) = read_obj(path)?;
            if t != triangles || p != parts {
                return Err(file_error(
                    path,
                    format!(
                        "its objects or faces differ from {} (an animation keeps one topology)",
                        first.display()
                    ),
                ));
            }
            frames.push(positions);
        }
        Ok(Self { triangles, parts, frames })
    }

    /// The files of an OBJ sequence: those in the directory of `pattern` whose names match
    /// it, `*` standing for any text (e.g. `bird/bird_*.obj`), sorted by name.
    pub fn sequence_files(pattern: &Path) -> Result<Vec<PathBuf>, MeshError> {
        let dir = pattern.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        let name = pattern.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        let Some((prefix, suffix)) = name.split_once('*') else {
            return Err(file_error(pattern, "the sequence pattern needs one `*` in its file name"));
        };
        let entries = std::fs::read_dir(dir).map_err(|e| file_error(dir, e))?;
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok())
            .map(|e| e.path())
            .filter(|p| {
                p.file_name().and_then(|n| n.to_str()).is_some_and(|n| {
                    n.len() >= prefix.len() + suffix.len() && n.starts_with(prefix) && n.ends_with(suffix)
                })
            })
            .collect();
        files.sort();
        if files.is_empty() {
            return Err(file_error(pattern, "no file matches"));
        }
        Ok(files)
    }
}

type ObjContents = (Vec<[u32; 3]>, Vec<(String, Range<usize>)>, Vec<[f64; 3]>);

fn read_obj(path: &Path) -> Result<ObjContents, MeshError> {
    let models = super::obj::load(path).map_err(|e| file_error(path, e))?;
    let (mut triangles, mut parts, mut positions) = (Vec::new(), Vec::new(), Vec::new());
    for m in &models {
        let offset = positions.len() as u32;
        for p in m.mesh.positions.chunks_exact(3) {
            let p = [p[0], p[1], p[2]];
            if p.iter().any(|x| !x.is_finite()) {
                return Err(file_error(path, format!("object {}: a coordinate is not finite", m.name)));
            }
            positions.push(p);
        }
        let first = triangles.len();
        for f in m.mesh.indices.chunks_exact(3) {
            triangles.push([f[0] + offset, f[1] + offset, f[2] + offset]);
        }
        if triangles.len() == first {
            return Err(file_error(path, format!("object {} has no faces", m.name)));
        }
        check_closed(&triangles[first..], &positions)
            .map_err(|e| file_error(path, format!("object {}: {e}", m.name)))?;
        parts.push((m.name.clone(), first..triangles.len()));
    }
    Ok((triangles, parts, positions))
}

/// Refuses a part that is not a closed surface: every edge (by its end positions, so vertices
/// an OBJ repeats for other texture or normal indices still join) must be shared by exactly
/// two of the part's triangles, traversed in opposite directions (consistently oriented).
fn check_closed(triangles: &[[u32; 3]], positions: &[[f64; 3]]) -> Result<(), String> {
    use std::collections::HashMap;
    let key = |v: u32| positions[v as usize].map(f64::to_bits);
    // (lower end, higher end) → (uses from lower to higher, uses from higher to lower)
    let mut edges: HashMap<([u64; 3], [u64; 3]), (u32, u32)> = HashMap::with_capacity(3 * triangles.len());
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (key(t[k]), key(t[(k + 1) % 3]));
            if a == b {
                continue;
            }
            let entry = edges.entry(if a < b { (a, b) } else { (b, a) }).or_insert((0, 0));
            if a < b {
                entry.0 += 1;
            } else {
                entry.1 += 1;
            }
        }
    }
    let point = |bits: [u64; 3]| bits.map(f64::from_bits);
    let mut bad: Vec<_> = edges.iter().filter(|(_, &(f, r))| !(f == 1 && r == 1)).collect();
    bad.sort_by(|a, b| a.0.cmp(b.0));
    match bad.first() {
        None => Ok(()),
        Some(((a, b), &(f, r))) => Err(format!(
            "not a closed, consistently oriented surface: the edge from {:?} to {:?} is used by {} triangle(s) ({f} one way, {r} the other; a closed surface uses every edge twice, once each way), and {} edge(s) like it",
            point(*a),
            point(*b),
            f + r,
            bad.len()
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tetrahedron and a shifted copy as two parts, over two frames.
    fn two_tetrahedra() -> SurfaceAnimation {
        let tet = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let mut triangles: Vec<[u32; 3]> = faces.to_vec();
        triangles.extend(faces.iter().map(|f| f.map(|v| v + 4)));
        let frame = |shift: f64| -> Vec<[f64; 3]> {
            tet.iter()
                .copied()
                .chain(tet.iter().map(|p| [p[0] + 2.0 + shift, p[1] + 1.0 / 3.0, p[2]]))
                .collect()
        };
        SurfaceAnimation {
            triangles,
            parts: vec![("a".into(), 0..4), ("b".into(), 4..8)],
            frames: vec![frame(0.0), frame(0.1)],
        }
    }

    #[test]
    fn an_obj_sequence_round_trips_exactly_and_a_changed_topology_is_refused() {
        let dir = std::env::temp_dir().join(format!("galerkin-anim-{}", std::process::id()));
        let anim = two_tetrahedra();
        anim.write_sequence(&dir, "shape").expect("written");
        let files = SurfaceAnimation::sequence_files(&dir.join("shape_*.obj")).expect("listed");
        assert_eq!(files.len(), 2);
        let back = SurfaceAnimation::read_sequence(&files).expect("read");
        // The reader numbers vertices in the order the faces first use them: compare corners.
        assert_eq!((back.triangles.len(), back.frame_count()), (anim.triangles.len(), 2));
        for k in 0..2 {
            for t in 0..anim.triangles.len() {
                assert_eq!(back.triangle_at(k, t), anim.triangle_at(k, t), "frame {k} triangle {t}");
            }
        }
        assert_eq!(back.parts, anim.parts);
        // The union's distance: inside part b at frame 1, outside both elsewhere.
        let sdf = back.sdf(1).expect("sdf");
        assert!(sdf.distance([2.2, 0.43, 0.1]) < 0.0);
        assert!(sdf.distance([1.5, 1.5, 1.5]) > 0.0);
        // A third frame with one face's corners numbered from another corner: the same closed
        // surface, another topology.
        let text = std::fs::read_to_string(&files[1]).expect("read");
        let turned: String = text
            .lines()
            .map(|l| if l == "f 6 7 8" { "f 7 8 6\n".to_string() } else { format!("{l}\n") })
            .collect();
        assert_ne!(turned, text);
        std::fs::write(dir.join("shape_0002.obj"), &turned).expect("write");
        let files = SurfaceAnimation::sequence_files(&dir.join("shape_*.obj")).expect("listed");
        let err = SurfaceAnimation::read_sequence(&files).expect_err("topology changed").to_string();
        assert!(err.contains("shape_0002.obj") && err.contains("differ"), "{err}");
        // A frame missing a face: its object is not closed, refused naming the file and object.
        let cut: String = text.lines().filter(|l| *l != "f 6 7 8").map(|l| format!("{l}\n")).collect();
        std::fs::write(dir.join("shape_0002.obj"), cut).expect("write");
        let files = SurfaceAnimation::sequence_files(&dir.join("shape_*.obj")).expect("listed");
        let err = SurfaceAnimation::read_sequence(&files).expect_err("an open part").to_string();
        assert!(
            err.contains("shape_0002.obj") && err.contains("object b") && err.contains("not a closed"),
            "{err}"
        );
        assert!(SurfaceAnimation::sequence_files(&dir.join("shape.obj")).is_err());
        std::fs::remove_dir_all(&dir).expect("clean up");
    }
}
