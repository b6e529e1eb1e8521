//! The `.gst` file: a compact, versioned, memory-mappable binary of a spacetime data set,
//! sorted by lowest time, for data larger than memory (the out-of-core format).
//!
//! Layout (little-endian; version 1):
//!
//! | bytes | content |
//! |---|---|
//! | 0–7 | magic `GLKN-GST` |
//! | 8–11 | version (1) |
//! | 12–15 | record size (240) |
//! | 16–23 | element count `n` |
//! | 24–27 | material count `m` (1 ..= 64) |
//! | 28–31 | zero |
//! | 32–95 | summary: x_lo, y_lo, x_hi, y_hi, t_lo, t_hi, longest element duration, largest centroid \|v\| (f64) |
//! | 96–103 | byte offset of the records (4096) |
//! | 104–111 | byte offset of the index (4096 + 240 n) |
//! | 256– | materials: (λ, μ, ρ) f64 each |
//! | 4096– | `n` [`ElementRecord`]s, ascending lowest time |
//! | 4096 + 240 n – | the index: `n` lowest times (f32), the same order |
//!
//! The file ends right after the index. Opening checks the header, the size and that the index
//! is sorted and finite; records are checked when the renderer first reads them (an error names
//! the file and the element), so opening a 2·10⁷-element file reads 4096 + 4n bytes.
//! Writing goes to a uniquely named temporary beside the file ([`crate::atomic_file`]), renamed
//! when complete: a failed write leaves nothing, and two writers of one name never mix.

use std::fs::File;
use std::io::{BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use super::cubic::Material;
use super::data::{DataSummary, SpacetimeData};
use super::error::SpacetimeError;
use super::record::ElementRecord;

/// The file's first eight bytes.
pub const MAGIC: [u8; 8] = *b"GLKN-GST";
/// The version this build reads and writes.
pub const VERSION: u32 = 1;
/// Bytes before the records.
pub const HEADER_BYTES: usize = 4096;
/// The most materials a file holds.
pub const MAX_MATERIALS: usize = 64;
const MATERIALS_AT: usize = 256;

fn file_error(path: &Path, detail: impl Into<String>) -> SpacetimeError {
    SpacetimeError::File { path: path.to_path_buf(), detail: detail.into() }
}

fn header(materials: &[Material], s: &DataSummary) -> Vec<u8> {
    let mut h = vec![0u8; HEADER_BYTES];
    h[0..8].copy_from_slice(&MAGIC);
    h[8..12].copy_from_slice(&VERSION.to_le_bytes());
    h[12..16].copy_from_slice(&(ElementRecord::BYTES as u32).to_le_bytes());
    h[16..24].copy_from_slice(&s.elements.to_le_bytes());
    h[24..28].copy_from_slice(&(materials.len() as u32).to_le_bytes());
    let f = [
        s.space_lo[0],
        s.space_lo[1],
        s.space_hi[0],
        s.space_hi[1],
        s.time[0],
        s.time[1],
        s.longest,
        s.max_speed,
    ];
    for (k, v) in f.iter().enumerate() {
        h[32 + 8 * k..40 + 8 * k].copy_from_slice(&v.to_le_bytes());
    }
    let records_at = HEADER_BYTES as u64;
    let index_at = records_at + s.elements * ElementRecord::BYTES as u64;
    h[96..104].copy_from_slice(&records_at.to_le_bytes());
    h[104..112].copy_from_slice(&index_at.to_le_bytes());
    for (i, m) in materials.iter().enumerate() {
        for (k, v) in [m.lambda, m.mu, m.density].iter().enumerate() {
            let at = MATERIALS_AT + 24 * i + 8 * k;
            h[at..at + 8].copy_from_slice(&v.to_le_bytes());
        }
    }
    h
}

/// Writes a `.gst` file element by element, in ascending lowest time, without holding the
/// data set: records stream to disk, the index (4 bytes per element) is kept until
/// [`GstWriter::finish`].
pub struct GstWriter {
    path: PathBuf,
    partial: PathBuf,
    out: Option<BufWriter<crate::atomic_file::AtomicFile>>,
    materials: Vec<Material>,
    lowest: Vec<f32>,
    summary: DataSummary,
}

impl GstWriter {
    /// Starts `path` (written to a temporary beside it until finished) for data with
    /// `materials`.
    pub fn create(path: &Path, materials: &[Material]) -> Result<Self, SpacetimeError> {
        if materials.is_empty() || materials.len() > MAX_MATERIALS {
            return Err(file_error(
                path,
                format!("needs 1 to {MAX_MATERIALS} materials, got {}", materials.len()),
            ));
        }
        for (i, m) in materials.iter().enumerate() {
            if let Some(what) = m.problem() {
                return Err(file_error(path, format!("material {i} {what}")));
            }
        }
        let file =
            crate::atomic_file::AtomicFile::create(path).map_err(|e| file_error(path, e.to_string()))?;
        let partial = file.temp_path().to_path_buf();
        let mut out = BufWriter::with_capacity(1 << 20, file);
        out.write_all(&vec![0u8; HEADER_BYTES]).map_err(|e| file_error(&partial, e.to_string()))?;
        Ok(Self {
            path: path.to_path_buf(),
            partial,
            out: Some(out),
            materials: materials.to_vec(),
            lowest: Vec::new(),
            summary: DataSummary::empty(),
        })
    }

    /// Appends one element; it must pass [`ElementRecord::problem`] and not start earlier
    /// than the previous one.
    pub fn push(&mut self, r: &ElementRecord) -> Result<(), SpacetimeError> {
        let e = self.lowest.len();
        if let Some(what) = r.problem(self.materials.len()) {
            return Err(file_error(&self.path, format!("element {e}: {what}")));
        }
        let t = r.lowest_time();
        if let Some(&last) = self.lowest.last() {
            if t < last {
                return Err(file_error(
                    &self.path,
                    format!("element {e}: lowest time {t} is earlier than element {}'s {last}: elements must come in ascending lowest time", e - 1),
                ));
            }
        }
        let out = self.out.as_mut().expect("open until finished");
        out.write_all(bytemuck::bytes_of(r)).map_err(|x| file_error(&self.partial, x.to_string()))?;
        self.lowest.push(t);
        self.summary.add(r, &self.materials);
        Ok(())
    }

    /// Elements written so far.
    pub fn len(&self) -> usize {
        self.lowest.len()
    }

    /// Nothing written yet.
    pub fn is_empty(&self) -> bool {
        self.lowest.is_empty()
    }

    /// Writes the index and the header and moves the file to its name; returns the summary.
    pub fn finish(mut self) -> Result<DataSummary, SpacetimeError> {
        let mut out = self.out.take().expect("open until finished");
        let io = |e: std::io::Error| file_error(&self.partial, e.to_string());
        out.write_all(bytemuck::cast_slice(&self.lowest)).map_err(io)?;
        out.seek(SeekFrom::Start(0)).map_err(io)?;
        out.write_all(&header(&self.materials, &self.summary)).map_err(io)?;
        let file = out.into_inner().map_err(|e| file_error(&self.partial, e.to_string()))?;
        file.commit().map_err(|e| file_error(&self.path, e.to_string()))?;
        Ok(self.summary)
    }
}

/// Writes `data` to `path`.
pub fn write(path: &Path, data: &SpacetimeData) -> Result<DataSummary, SpacetimeError> {
    let mut w = GstWriter::create(path, data.materials())?;
    for r in data.records() {
        w.push(r)?;
    }
    w.finish()
}

fn read_u32(h: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(h[at..at + 4].try_into().expect("4 bytes"))
}
fn read_u64(h: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(h[at..at + 8].try_into().expect("8 bytes"))
}
fn read_f64(h: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(h[at..at + 8].try_into().expect("8 bytes"))
}

/// Opens a `.gst` file by memory-mapping it; checks the header, the file size, the
/// materials and that the index is sorted and finite (records are checked when first read).
pub fn open(path: &Path) -> Result<SpacetimeData, SpacetimeError> {
    let mut file = File::open(path).map_err(|e| file_error(path, e.to_string()))?;
    let size = file.metadata().map_err(|e| file_error(path, e.to_string()))?.len();
    let mut h = vec![0u8; HEADER_BYTES];
    file.read_exact(&mut h).map_err(|_| {
        file_error(path, format!("{size} bytes: too short for the {HEADER_BYTES}-byte header of a .gst file"))
    })?;
    if h[0..8] != MAGIC {
        return Err(file_error(path, "not a galerkin spacetime file (.gst): wrong magic bytes"));
    }
    let version = read_u32(&h, 8);
    if version != VERSION {
        return Err(file_error(path, format!("version {version}; this build reads version {VERSION}")));
    }
    let record = read_u32(&h, 12) as usize;
    if record != ElementRecord::BYTES {
        return Err(file_error(
            path,
            format!("records of {record} bytes; version {VERSION} has {}", ElementRecord::BYTES),
        ));
    }
    let n = read_u64(&h, 16);
    let m = read_u32(&h, 24) as usize;
    if m == 0 || m > MAX_MATERIALS {
        return Err(file_error(path, format!("{m} materials in the header (1 to {MAX_MATERIALS} allowed)")));
    }
    let records_at = read_u64(&h, 96);
    let index_at = read_u64(&h, 104);
    let expected = n
        .checked_mul(ElementRecord::BYTES as u64 + 4)
        .and_then(|b| b.checked_add(HEADER_BYTES as u64))
        .ok_or_else(|| file_error(path, format!("element count {n} is impossible")))?;
    if records_at != HEADER_BYTES as u64 || index_at != HEADER_BYTES as u64 + n * ElementRecord::BYTES as u64
    {
        return Err(file_error(
            path,
            format!("section offsets {records_at}, {index_at} disagree with {n} elements"),
        ));
    }
    if size != expected {
        let what = if size < expected { "truncated" } else { "has trailing bytes" };
        return Err(file_error(
            path,
            format!("{what}: {size} bytes, the header's {n} elements need {expected}"),
        ));
    }
    let mut materials = crate::limits::vec_for(m, "the materials").map_err(|e| file_error(path, e))?;
    for i in 0..m {
        let at = MATERIALS_AT + 24 * i;
        let mat =
            Material { lambda: read_f64(&h, at), mu: read_f64(&h, at + 8), density: read_f64(&h, at + 16) };
        if let Some(what) = mat.problem() {
            return Err(file_error(path, format!("material {i} {what}")));
        }
        materials.push(mat);
    }
    let f: Vec<f64> = (0..8).map(|k| read_f64(&h, 32 + 8 * k)).collect();
    if f.iter().any(|x| !x.is_finite()) && n > 0 {
        return Err(file_error(path, "the header's summary is not finite"));
    }
    let summary = DataSummary {
        elements: n,
        space_lo: [f[0], f[1]],
        space_hi: [f[2], f[3]],
        time: [f[4], f[5]],
        longest: f[6],
        max_speed: f[7],
    };
    // SAFETY: the map is read-only; the file could be changed by another process while mapped,
    // which would change what we read (not memory safety for plain-old-data records and f32),
    // and every record is checked before use.
    let map =
        unsafe { memmap2::Mmap::map(&file) }.map_err(|e| file_error(path, format!("cannot map: {e}")))?;
    let records = records_at as usize..index_at as usize;
    let index = index_at as usize..size as usize;
    let lowest: &[f32] = bytemuck::cast_slice(&map[index.clone()]);
    for (e, w) in lowest.iter().enumerate() {
        if !w.is_finite() {
            return Err(file_error(path, format!("element {e}: lowest time in the index is not finite")));
        }
        if e > 0 && *w < lowest[e - 1] {
            return Err(file_error(path, format!("element {e}: the index is not sorted by lowest time")));
        }
    }
    if n > 0 && (f64::from(lowest[0]) < summary.time[0] || summary.longest < 0.0) {
        return Err(file_error(path, "the header's time range disagrees with the index"));
    }
    Ok(SpacetimeData::mapped(path, map, records, index, materials, summary))
}
