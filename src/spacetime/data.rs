//! A spacetime data set as the renderer reads it: [`ElementRecord`]s sorted by lowest time
//! with the index of lowest times beside them (seed 003 §4.1), the materials, and a summary —
//! either held in memory (from a [`SpacetimeMesh`]) or memory-mapped from a `.gst` file
//! ([`super::gst`]) so that only the pages of the elements a slice touches are ever read.

use std::ops::Range;
use std::path::{Path, PathBuf};

use super::cubic::{evaluate, Material};
use super::error::SpacetimeError;
use super::mesh::SpacetimeMesh;
use super::record::ElementRecord;

/// Facts about a data set that the renderer needs before touching any element.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DataSummary {
    /// Number of elements.
    pub elements: u64,
    /// Lower corner of the spatial bounding box.
    pub space_lo: [f64; 2],
    /// Upper corner of the spatial bounding box.
    pub space_hi: [f64; 2],
    /// Lowest and highest vertex time.
    pub time: [f64; 2],
    /// The longest time span of one element (bounds the active range, §4.1).
    pub longest: f64,
    /// The largest |v| at an element centroid (sets the default height scale).
    pub max_speed: f64,
}

impl DataSummary {
    /// The summary of no elements.
    pub fn empty() -> Self {
        Self {
            elements: 0,
            space_lo: [f64::INFINITY; 2],
            space_hi: [f64::NEG_INFINITY; 2],
            time: [f64::INFINITY, f64::NEG_INFINITY],
            longest: 0.0,
            max_speed: 0.0,
        }
    }

    /// Adds one element.
    pub fn add(&mut self, r: &ElementRecord, materials: &[Material]) {
        let p = r.corner_points();
        for c in &p {
            for (k, &x) in c[..2].iter().enumerate() {
                self.space_lo[k] = self.space_lo[k].min(x);
                self.space_hi[k] = self.space_hi[k].max(x);
            }
            self.time[0] = self.time[0].min(c[2]);
            self.time[1] = self.time[1].max(c[2]);
        }
        self.longest = self.longest.max(f64::from(r.highest_time()) - f64::from(r.lowest_time()));
        let x: [f64; 3] = std::array::from_fn(|k| 0.25 * (p[0][k] + p[1][k] + p[2][k] + p[3][k]));
        let m = &materials[r.material as usize];
        let speed = evaluate(&r.frame(), m, &r.coefficients_f64(), x).speed;
        self.max_speed = self.max_speed.max(speed);
        self.elements += 1;
    }

    /// The larger side of the spatial bounding box.
    pub fn size(&self) -> f64 {
        (self.space_hi[0] - self.space_lo[0]).max(self.space_hi[1] - self.space_lo[1])
    }

    /// The centre of the spatial bounding box.
    pub fn centre(&self) -> [f64; 2] {
        [0.5 * (self.space_lo[0] + self.space_hi[0]), 0.5 * (self.space_lo[1] + self.space_hi[1])]
    }
}

enum Storage {
    Owned { records: Vec<ElementRecord>, lowest: Vec<f32> },
    Mapped { map: memmap2::Mmap, records: Range<usize>, lowest: Range<usize> },
}

/// Elements sorted by lowest time, in memory or memory-mapped.
pub struct SpacetimeData {
    path: Option<PathBuf>,
    materials: Vec<Material>,
    summary: DataSummary,
    storage: Storage,
    /// Elements known to pass [`ElementRecord::problem`] (all of an in-memory mesh, which was
    /// validated whole; none of a file until its pages are read).
    checked: Range<usize>,
}

impl SpacetimeData {
    /// The data of a validated `mesh` sorted by lowest time
    /// ([`SpacetimeMesh::sort_by_lowest_time`]).
    pub fn from_mesh(mesh: &SpacetimeMesh) -> Result<Self, SpacetimeError> {
        mesh.validate()?;
        let records: Vec<ElementRecord> = (0..mesh.tets.len()).map(|e| ElementRecord::of(mesh, e)).collect();
        let lowest: Vec<f32> = records.iter().map(ElementRecord::lowest_time).collect();
        if let Some(e) = lowest.windows(2).position(|w| w[1] < w[0]) {
            return Err(SpacetimeError::Invalid {
                element: e + 1,
                what: "elements are not sorted by lowest time (SpacetimeMesh::sort_by_lowest_time)".into(),
            });
        }
        // f32 rounding can make a valid f64 element degenerate: check the records too.
        if let Some((e, what)) =
            records.iter().enumerate().find_map(|(e, r)| Some((e, r.problem(usize::MAX)?)))
        {
            return Err(SpacetimeError::Invalid { element: e, what: format!("{what} (in f32)") });
        }
        let mut summary = DataSummary::empty();
        for r in &records {
            summary.add(r, &mesh.materials);
        }
        let n = records.len();
        Ok(Self {
            path: None,
            materials: mesh.materials.clone(),
            summary,
            storage: Storage::Owned { records, lowest },
            checked: 0..n,
        })
    }

    /// Data memory-mapped from a `.gst` file whose header and index were checked; see
    /// [`super::gst::open`].
    pub(crate) fn mapped(
        path: &Path,
        map: memmap2::Mmap,
        records: Range<usize>,
        lowest: Range<usize>,
        materials: Vec<Material>,
        summary: DataSummary,
    ) -> Self {
        Self {
            path: Some(path.to_path_buf()),
            materials,
            summary,
            storage: Storage::Mapped { map, records, lowest },
            checked: 0..0,
        }
    }

    /// The file the data are mapped from, if any.
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// The materials.
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// The summary.
    pub fn summary(&self) -> &DataSummary {
        &self.summary
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.lowest_times().len()
    }

    /// No elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The records (for mapped data, touching a range reads only its pages).
    pub fn records(&self) -> &[ElementRecord] {
        match &self.storage {
            Storage::Owned { records, .. } => records,
            // The header check put the record range at a page-aligned offset with a length that
            // is a multiple of the record size; the map is page-aligned.
            Storage::Mapped { map, records, .. } => bytemuck::cast_slice(&map[records.clone()]),
        }
    }

    /// Every element's lowest time, ascending (the index of §4.1).
    pub fn lowest_times(&self) -> &[f32] {
        match &self.storage {
            Storage::Owned { lowest, .. } => lowest,
            Storage::Mapped { map, lowest, .. } => bytemuck::cast_slice(&map[lowest.clone()]),
        }
    }

    /// The elements a plane at `t` may cut: lowest time in `[t − longest, t)`, with `t` as the
    /// device sees it (f32). Every element the plane cuts is in the range.
    pub fn active_range(&self, t: f64) -> Range<usize> {
        let t = f64::from(t as f32);
        let lowest = self.lowest_times();
        let lo = lowest.partition_point(|&x| f64::from(x) < t - self.summary.longest);
        let hi = lowest.partition_point(|&x| f64::from(x) < t);
        lo..hi
    }

    /// Checks the records in `range` (once per element for the life of the data): the
    /// problems of [`ElementRecord::problem`] and agreement with the index of lowest times.
    /// The error names the file and the element.
    pub fn check(&mut self, range: Range<usize>) -> Result<(), SpacetimeError> {
        if self.checked.start <= range.start && range.end <= self.checked.end {
            return Ok(());
        }
        let materials = self.materials.len();
        let lowest = self.lowest_times();
        for (k, r) in self.records()[range.clone()].iter().enumerate() {
            let e = range.start + k;
            let duration = f64::from(r.highest_time()) - f64::from(r.lowest_time());
            let problem = r.problem(materials).or_else(|| {
                if r.lowest_time() != lowest[e] {
                    Some(format!(
                        "the index says lowest time {} but the corners say {}",
                        lowest[e],
                        r.lowest_time()
                    ))
                } else if duration > self.summary.longest {
                    Some(format!(
                        "spans {duration} in time, longer than the header's longest {}",
                        self.summary.longest
                    ))
                } else {
                    None
                }
            });
            if let Some(what) = problem {
                return Err(match &self.path {
                    Some(path) => {
                        SpacetimeError::File { path: path.clone(), detail: format!("element {e}: {what}") }
                    }
                    None => SpacetimeError::Invalid { element: e, what },
                });
            }
        }
        self.checked = range;
        Ok(())
    }

    /// The data as a mesh (f64 values of the f32 records; vertices shared where corners are
    /// bit-identical), for conversion to other formats and for CPU references.
    pub fn to_mesh(&self) -> SpacetimeMesh {
        use std::collections::HashMap;
        let mut index: HashMap<[u32; 3], u32> = HashMap::new();
        let mut mesh = SpacetimeMesh { materials: self.materials.clone(), ..Default::default() };
        for r in self.records() {
            let tet = std::array::from_fn(|i| {
                let key = [0, 1, 2].map(|k| r.corners[3 * i + k].to_bits());
                *index.entry(key).or_insert_with(|| {
                    mesh.vertices.push(key.map(|b| f64::from(f32::from_bits(b))));
                    (mesh.vertices.len() - 1) as u32
                })
            });
            mesh.tets.push(tet);
            mesh.fields.push(super::mesh::ElementField {
                frame: r.frame(),
                material: r.material,
                coefficients: r.coefficients_f64(),
            });
        }
        mesh
    }
}
