//! The scene as seed 000 §8 sees it: one triangle mesh of fixed topology whose vertex
//! positions `g` change with the design parameters, with an RGB albedo per face and a kind per
//! face (a surface, or an opening — window or skylight — through which light enters).
//!
//! Per face `i` (Eq. 15, Table 2): the centroid `cᵢ`, the normal `nᵢ = (g_{i,1} − g_{i,0}) ×
//! (g_{i,2} − g_{i,0})` (not normalised: its length is twice the area), and the area `Aᵢ`.

use glam::DVec3;

use super::error::RadiosityError;

/// What a face is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FaceKind {
    /// A wall, floor, ceiling or piece of furniture: reflects with its albedo.
    Surface,
    /// A window pane: an opening to the sky (an area light in [`LightMode::Area`]).
    ///
    /// [`LightMode::Area`]: super::LightMode::Area
    Window,
    /// The skylight: an opening in the living room's ceiling.
    Skylight,
}

impl FaceKind {
    /// Whether light enters through this face (a window or the skylight).
    pub fn is_opening(self) -> bool {
        !matches!(self, Self::Surface)
    }
}

/// A triangle mesh with per-face material.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneMesh {
    /// Vertex positions: the geometry `g` (3 values per vertex).
    pub vertices: Vec<DVec3>,
    /// Triangles, counter-clockwise seen from the side the face lights (its normal's side).
    pub faces: Vec<[u32; 3]>,
    /// RGB albedo `ρ` per face (0 for openings: light leaving through them is lost).
    pub albedo: Vec<[f64; 3]>,
    /// Kind per face.
    pub kind: Vec<FaceKind>,
    /// Index into [`SceneMesh::part_names`] per face.
    pub part: Vec<u16>,
    /// Names of the scene's parts ("living south wall", "bed", …), for errors and statistics.
    pub part_names: Vec<String>,
}

/// Per-face geometry (Eq. 15's `cᵢ`, `nᵢ`, `Aᵢ`).
#[derive(Clone, Debug, PartialEq)]
pub struct FaceGeometry {
    /// Centroids `cᵢ`.
    pub centroids: Vec<DVec3>,
    /// Unnormalised normals `nᵢ` (length `2Aᵢ`).
    pub normals: Vec<DVec3>,
    /// Areas `Aᵢ`.
    pub areas: Vec<f64>,
    /// Sums of the squared edge lengths `Lᵢ` (quadratic in `g`; the near-field term of
    /// [`crate::radiosity::form_factor`]).
    pub edge_squares: Vec<f64>,
}

impl SceneMesh {
    /// Number of faces `n`.
    pub fn len(&self) -> usize {
        self.faces.len()
    }

    /// Whether there are no faces.
    pub fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }

    /// The geometry vector `g` (x, y, z per vertex), the input of Table 2.
    pub fn g(&self) -> Vec<f64> {
        self.vertices.iter().flat_map(|v| v.to_array()).collect()
    }

    /// The three corners of face `i`.
    pub fn corners(&self, i: usize) -> [DVec3; 3] {
        self.faces[i].map(|v| self.vertices[v as usize])
    }

    /// Centroids, normals and areas of every face.
    pub fn geometry(&self) -> FaceGeometry {
        let n = self.len();
        let (mut centroids, mut normals, mut areas, mut edge_squares) =
            (Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n));
        for i in 0..n {
            let [a, b, c] = self.corners(i);
            let normal = (b - a).cross(c - a);
            centroids.push((a + b + c) / 3.0);
            normals.push(normal);
            areas.push(0.5 * normal.length());
            edge_squares.push((b - a).length_squared() + (c - b).length_squared() + (a - c).length_squared());
        }
        FaceGeometry { centroids, normals, areas, edge_squares }
    }

    /// Name of the part face `i` belongs to.
    pub fn part_of(&self, i: usize) -> &str {
        self.part_names.get(self.part[i] as usize).map_or("?", String::as_str)
    }

    /// Checks lengths, indices, finiteness and that no face is degenerate (area below
    /// 10⁻¹⁰ of the squared bounding-box diagonal), naming the face or vertex.
    pub fn validate(&self) -> Result<(), RadiosityError> {
        let n = self.faces.len();
        for (what, len) in
            [("albedo", self.albedo.len()), ("kind", self.kind.len()), ("part", self.part.len())]
        {
            if len != n {
                return Err(RadiosityError::Mesh(format!("{what}: {len} entries for {n} faces")));
            }
        }
        if let Some(v) = self.vertices.iter().position(|v| !v.is_finite()) {
            return Err(RadiosityError::NotFinite { what: format!("vertex {v}") });
        }
        for (i, f) in self.faces.iter().enumerate() {
            if let Some(&v) = f.iter().find(|&&v| v as usize >= self.vertices.len()) {
                return Err(RadiosityError::Mesh(format!(
                    "face {i}: vertex index {v} is out of range ({} vertices)",
                    self.vertices.len()
                )));
            }
            if self.part[i] as usize >= self.part_names.len() {
                return Err(RadiosityError::Mesh(format!("face {i}: part {} is not named", self.part[i])));
            }
        }
        if let Some(i) = self.albedo.iter().position(|a| a.iter().any(|x| !x.is_finite())) {
            return Err(RadiosityError::NotFinite { what: format!("albedo of face {i}") });
        }
        if let Some(i) = self.albedo.iter().position(|a| a.iter().any(|x| !(0.0..1.0).contains(x))) {
            return Err(RadiosityError::Mesh(format!(
                "face {i}: albedo {:?} is outside [0, 1)",
                self.albedo[i]
            )));
        }
        let (lo, hi) = self.bounds();
        let scale = if self.vertices.is_empty() { 1.0 } else { (hi - lo).length_squared().max(1e-300) };
        let geometry = self.geometry();
        for (i, &area) in geometry.areas.iter().enumerate() {
            if area.is_nan() || area <= 1e-10 * scale {
                return Err(RadiosityError::DegenerateFace {
                    face: i,
                    part: self.part_of(i).to_string(),
                    area,
                });
            }
        }
        Ok(())
    }

    /// The bounding box of the vertices (min, max corners).
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.vertices
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), v| (lo.min(*v), hi.max(*v)))
    }

    /// The same topology with new vertex positions `g` (3 per vertex); validated.
    pub fn with_g(&self, g: &[f64]) -> Result<Self, RadiosityError> {
        if g.len() != 3 * self.vertices.len() {
            return Err(RadiosityError::Mesh(format!(
                "geometry vector: {} values for {} vertices",
                g.len(),
                self.vertices.len()
            )));
        }
        let mut mesh = self.clone();
        mesh.vertices = g.chunks_exact(3).map(|c| DVec3::new(c[0], c[1], c[2])).collect();
        mesh.validate()?;
        Ok(mesh)
    }

    /// A parallelogram `origin + a·u + b·v`, `a, b ∈ [0, 1]`, split into `cells × cells`
    /// cells of two triangles each, lit on the side of `u × v`: the closed-form test patches.
    pub fn parallelogram(
        origin: DVec3,
        u: DVec3,
        v: DVec3,
        cells: usize,
        albedo: [f64; 3],
        part: &str,
    ) -> Self {
        let m = cells.max(1);
        let index = |i: usize, j: usize| (i * (m + 1) + j) as u32;
        let mut vertices = Vec::with_capacity((m + 1) * (m + 1));
        for i in 0..=m {
            for j in 0..=m {
                vertices.push(origin + u * (i as f64 / m as f64) + v * (j as f64 / m as f64));
            }
        }
        let mut faces = Vec::with_capacity(2 * m * m);
        for i in 0..m {
            for j in 0..m {
                faces.push([index(i, j), index(i + 1, j), index(i + 1, j + 1)]);
                faces.push([index(i, j), index(i + 1, j + 1), index(i, j + 1)]);
            }
        }
        let n = faces.len();
        Self {
            vertices,
            faces,
            albedo: vec![albedo; n],
            kind: vec![FaceKind::Surface; n],
            part: vec![0; n],
            part_names: vec![part.to_string()],
        }
    }

    /// Appends `other` (its vertices, faces and parts).
    pub fn append(&mut self, other: &SceneMesh) {
        let offset = self.vertices.len() as u32;
        let part_offset = self.part_names.len() as u16;
        self.vertices.extend_from_slice(&other.vertices);
        self.faces.extend(other.faces.iter().map(|f| f.map(|v| v + offset)));
        self.albedo.extend_from_slice(&other.albedo);
        self.kind.extend_from_slice(&other.kind);
        self.part.extend(other.part.iter().map(|p| p + part_offset));
        self.part_names.extend_from_slice(&other.part_names);
    }
}
