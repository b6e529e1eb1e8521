//! The binary encodings of VTK XML data arrays (`vtkXMLWriter`): base64 text, block headers
//! of UInt32 or UInt64 words, and the three block compressors VTK offers.
//!
//! An uncompressed array is `[n bytes] data`. A compressed one is split into blocks of a
//! fixed uncompressed size and framed as `[blocks, block size, last block's size (0: full),
//! compressed size of each block…]` followed by the compressed blocks: zlib streams
//! (`vtkZLibDataCompressor`), raw LZ4 blocks (`vtkLZ4DataCompressor`) or xz streams
//! (`vtkLZMADataCompressor`). In base64 (inline `binary`, and appended data with
//! `encoding="base64"`) VTK encodes the header and the data as **separate padded runs**; every
//! run is a whole number of 4-character groups, so the runs are decoded one after another.
//!
//! Decompression is bounded: the sizes a header declares are checked against what the array
//! can hold (its tuples × components × type size, from the `<Piece>`'s counts) before any block
//! is inflated, and each block is inflated to at most its declared size.

use base64::Engine;

/// The block compressor of a file (`compressor` attribute of `<VTKFile>`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compressor {
    /// No compression.
    None,
    /// `vtkZLibDataCompressor`: zlib streams.
    Zlib,
    /// `vtkLZ4DataCompressor`: raw LZ4 blocks.
    Lz4,
    /// `vtkLZMADataCompressor`: xz streams.
    Lzma,
}

impl Compressor {
    /// The compressor named by a `compressor` attribute (absent or empty: none).
    pub fn from_attribute(name: Option<&str>) -> Result<Self, String> {
        match name {
            None | Some("") => Ok(Self::None),
            Some("vtkZLibDataCompressor") => Ok(Self::Zlib),
            Some("vtkLZ4DataCompressor") => Ok(Self::Lz4),
            Some("vtkLZMADataCompressor") => Ok(Self::Lzma),
            Some(other) => Err(format!(
                "compressor {other:?} is not one of VTK's (vtkZLibDataCompressor, vtkLZ4DataCompressor, vtkLZMADataCompressor)"
            )),
        }
    }

    /// VTK's class name of the compressor (`vtkLZ4DataCompressor`), for errors.
    pub fn vtk_name(self) -> &'static str {
        match self {
            Self::None => "uncompressed",
            Self::Zlib => "vtkZLibDataCompressor",
            Self::Lz4 => "vtkLZ4DataCompressor",
            Self::Lzma => "vtkLZMADataCompressor",
        }
    }

    /// Inflates `z` to exactly `size` bytes, never more.
    fn inflate(self, z: &[u8], size: usize) -> Result<Vec<u8>, String> {
        let out = match self {
            Self::None => z.to_vec(),
            Self::Zlib => miniz_oxide::inflate::decompress_to_vec_zlib_with_limit(z, size)
                .map_err(|e| format!("bad zlib data ({:?})", e.status))?,
            Self::Lz4 => lz4_flex::block::decompress(z, size).map_err(|e| format!("bad LZ4 data ({e})"))?,
            Self::Lzma => {
                let mut out = Capped { bytes: Vec::new(), cap: size };
                lzma_rs::xz_decompress(&mut std::io::BufReader::new(z), &mut out)
                    .map_err(|e| format!("bad LZMA (xz) data ({e})"))?;
                out.bytes
            }
        };
        if out.len() != size {
            return Err(format!("a block inflates to {} bytes, its header says {size}", out.len()));
        }
        Ok(out)
    }
}

/// A writer that refuses to grow past `cap` bytes (bounds the xz decoder's output).
struct Capped {
    bytes: Vec<u8>,
    cap: usize,
}

impl std::io::Write for Capped {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.bytes.len() + buf.len() > self.cap {
            return Err(std::io::Error::other(format!("more than the declared {} bytes", self.cap)));
        }
        self.bytes.extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Decodes base64 text made of one or more padded runs (whitespace ignored).
pub fn base64_runs(text: &[u8]) -> Result<Vec<u8>, String> {
    let clean: Vec<u8> = text.iter().copied().filter(|c| !c.is_ascii_whitespace()).collect();
    if !clean.len().is_multiple_of(4) {
        return Err(format!("{} base64 characters is not a whole number of 4-character groups", clean.len()));
    }
    let engine = base64::engine::general_purpose::STANDARD;
    let mut out = Vec::with_capacity(clean.len() / 4 * 3);
    let mut start = 0;
    for (g, group) in clean.chunks_exact(4).enumerate() {
        // A group with padding ends a run.
        if group.contains(&b'=') || 4 * (g + 1) == clean.len() {
            engine
                .decode_vec(&clean[start..4 * (g + 1)], &mut out)
                .map_err(|e| format!("bad base64 at character {}: {e}", start))?;
            start = 4 * (g + 1);
        }
    }
    Ok(out)
}

/// How the binary blocks of a file are framed.
#[derive(Clone, Copy, Debug)]
pub struct Framing {
    /// `header_type="UInt64"` (else UInt32).
    pub header_u64: bool,
    /// The block compressor.
    pub compressor: Compressor,
}

impl Framing {
    fn header_bytes(&self) -> usize {
        if self.header_u64 {
            8
        } else {
            4
        }
    }

    fn word(&self, b: &[u8], k: usize) -> Option<usize> {
        let h = self.header_bytes();
        let w = b.get(k.checked_mul(h)?..(k + 1).checked_mul(h)?)?;
        if self.header_u64 {
            usize::try_from(u64::from_le_bytes(w.try_into().ok()?)).ok()
        } else {
            Some(u32::from_le_bytes(w.try_into().ok()?) as usize)
        }
    }

    /// Decodes one array (its header and data) from `b`, refusing before inflating anything
    /// if the header declares more than `limit` bytes; returns the data and the bytes used.
    pub fn block(&self, b: &[u8], limit: usize) -> Result<(Vec<u8>, usize), String> {
        let h = self.header_bytes();
        let too_big =
            |n: usize| format!("the header declares {n} bytes, more than the array can hold ({limit})");
        if self.compressor == Compressor::None {
            let n = self.word(b, 0).ok_or("truncated block header")?;
            if n > limit {
                return Err(too_big(n));
            }
            let data = b
                .get(h..h.saturating_add(n))
                .ok_or_else(|| format!("truncated: a block of {n} bytes is cut short"))?;
            return Ok((data.to_vec(), h + n));
        }
        // A compressed array starts with words of `h` bytes: block count, block size, last
        // block's size, then each block's compressed size (vtkXMLWriter's block header).
        let short = |words: usize| {
            format!(
                "the {} block header is cut short: {words} words of {h} bytes (header_type={}) need {} bytes, the array has {}",
                self.compressor.vtk_name(),
                if self.header_u64 { "UInt64" } else { "UInt32" },
                words.saturating_mul(h),
                b.len()
            )
        };
        let word = |k: usize| self.word(b, k).ok_or_else(|| short(k + 1));
        let (blocks, block_size, last_size) = (word(0)?, word(1)?, word(2)?);
        // The uncompressed total the header declares, checked before the sizes are read.
        let total = match blocks {
            0 => 0,
            _ => {
                let last = if last_size == 0 { block_size } else { last_size };
                if last > block_size {
                    return Err(format!(
                        "last block of {last} bytes is larger than the block size {block_size}"
                    ));
                }
                (blocks - 1)
                    .checked_mul(block_size)
                    .and_then(|t| t.checked_add(last))
                    .ok_or_else(|| too_big(usize::MAX))?
            }
        };
        if total > limit {
            return Err(too_big(total));
        }
        let mut at = blocks.checked_add(3).and_then(|w| w.checked_mul(h)).ok_or_else(|| short(blocks))?;
        if b.len() < at {
            return Err(short(blocks + 3));
        }
        let mut out = Vec::with_capacity(total);
        for k in 0..blocks {
            let size = word(3 + k)?;
            let z = b.get(at..at.saturating_add(size)).ok_or("truncated compressed block")?;
            let expect = if k + 1 == blocks && last_size != 0 { last_size } else { block_size };
            let d = self.compressor.inflate(z, expect).map_err(|e| format!("block {k}: {e}"))?;
            out.extend_from_slice(&d);
            at += size;
        }
        Ok((out, at))
    }
}

/// The size in bytes of one value of VTK type `ty`.
pub fn type_size(ty: &str) -> Option<usize> {
    Some(match ty {
        "Float64" | "Int64" | "UInt64" => 8,
        "Float32" | "Int32" | "UInt32" => 4,
        "Int16" | "UInt16" => 2,
        "Int8" | "UInt8" => 1,
        _ => return None,
    })
}

/// Numbers of a DataArray of VTK type `ty` from little-endian bytes.
pub fn numbers(ty: &str, b: &[u8]) -> Result<Vec<f64>, String> {
    macro_rules! conv {
        ($t:ty) => {{
            const N: usize = std::mem::size_of::<$t>();
            if !b.len().is_multiple_of(N) {
                return Err(format!("{} bytes is not a whole number of {ty} values", b.len()));
            }
            b.chunks_exact(N).map(|c| <$t>::from_le_bytes(c.try_into().expect("N bytes")) as f64).collect()
        }};
    }
    Ok(match ty {
        "Float64" => conv!(f64),
        "Float32" => conv!(f32),
        "Int64" => conv!(i64),
        "UInt64" => conv!(u64),
        "Int32" => conv!(i32),
        "UInt32" => conv!(u32),
        "Int16" => conv!(i16),
        "UInt16" => conv!(u16),
        "Int8" => conv!(i8),
        "UInt8" => conv!(u8),
        other => return Err(format!("unsupported type {other}")),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_runs_decode_the_rfc_4648_vectors_and_concatenated_padded_runs() {
        for (plain, text) in
            [("", ""), ("f", "Zg=="), ("fo", "Zm8="), ("foo", "Zm9v"), ("foobar", "Zm9vYmFy")]
        {
            assert_eq!(base64_runs(text.as_bytes()).unwrap(), plain.as_bytes());
        }
        // Two runs, as VTK writes a header and its data: "fo" then "foob".
        assert_eq!(base64_runs(b"Zm8=\n  Zm9vYg==").unwrap(), b"fofoob");
        assert!(base64_runs(b"Zm9v!AAA").is_err());
        assert!(base64_runs(b"Zm9").is_err());
    }

    #[test]
    fn a_header_declaring_more_than_the_array_holds_is_refused_before_inflating() {
        let framing = Framing { header_u64: false, compressor: Compressor::Zlib };
        // One block of 2^31 bytes declared; nothing follows.
        let mut b = Vec::new();
        for w in [1u32, 1 << 31, 0, 10] {
            b.extend_from_slice(&w.to_le_bytes());
        }
        b.extend_from_slice(&[0u8; 10]);
        let e = framing.block(&b, 1 << 20).unwrap_err();
        assert!(e.contains("declares 2147483648 bytes"), "{e}");
        // A zlib block that inflates past its declared size is cut off at that size.
        let z = miniz_oxide::deflate::compress_to_vec_zlib(&[7u8; 100_000], 6);
        let mut b = Vec::new();
        for w in [1u32, 1000, 0, z.len() as u32] {
            b.extend_from_slice(&w.to_le_bytes());
        }
        b.extend_from_slice(&z);
        assert!(framing.block(&b, 1 << 20).is_err());
    }

    #[test]
    fn a_cut_short_block_header_names_the_compressor_and_the_sizes() {
        // Two LZ4 blocks declared with 32-bit words, but only the first four words present.
        let framing = Framing { header_u64: false, compressor: Compressor::Lz4 };
        let mut b = Vec::new();
        for w in [2u32, 64, 0, 10] {
            b.extend_from_slice(&w.to_le_bytes());
        }
        let e = framing.block(&b, 1 << 20).unwrap_err();
        for word in
            ["vtkLZ4DataCompressor", "cut short", "5 words of 4 bytes", "header_type=UInt32", "has 16"]
        {
            assert!(e.contains(word), "{e:?} does not say {word:?}");
        }
        // Fewer bytes than the three leading words.
        let framing = Framing { header_u64: true, compressor: Compressor::Zlib };
        let e = framing.block(&[1, 0, 0], 1 << 20).unwrap_err();
        assert!(e.contains("vtkZLibDataCompressor") && e.contains("UInt64") && e.contains("has 3"), "{e}");
    }
}
