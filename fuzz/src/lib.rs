//! What the fuzz targets share: the loaders read paths, so each input is written to a scratch
//! file of this process (libFuzzer runs one input at a time per process) before it is read.

use std::path::PathBuf;

/// A scratch directory of this process, made once.
pub fn scratch_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("galerkin-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch directory");
    dir
}

/// Writes `bytes` to the scratch file `name` and returns its path.
pub fn scratch_file(name: &str, bytes: &[u8]) -> PathBuf {
    let path = scratch_dir().join(name);
    std::fs::write(&path, bytes).expect("the scratch file");
    path
}

/// `data` cut at the separator line `--8<--` into at most `n` parts (the rest empty).
///
/// The separator is found with `memchr::memmem` rather than a comparison per window: under
/// libFuzzer every `==` on slices is a traced `memcmp`, and the window-by-window search took
/// a third of the reduced-model target's time.
pub fn parts(data: &[u8], n: usize) -> Vec<&[u8]> {
    const SEP: &[u8] = b"\n--8<--\n";
    let finder = memchr::memmem::Finder::new(SEP);
    let mut out = Vec::with_capacity(n);
    let mut rest = data;
    while out.len() + 1 < n {
        match finder.find(rest) {
            Some(i) => {
                out.push(&rest[..i]);
                rest = &rest[i + SEP.len()..];
            }
            None => break,
        }
    }
    out.push(rest);
    out.resize(n, &[]);
    out
}

#[cfg(test)]
mod tests {
    use super::parts;

    #[test]
    fn parts_cut_at_the_separator_and_pad() {
        let data = b"a\n--8<--\nbb\n--8<--\nccc";
        assert_eq!(parts(data, 3), vec![&b"a"[..], b"bb", b"ccc"]);
        assert_eq!(parts(data, 2), vec![&b"a"[..], b"bb\n--8<--\nccc"]);
        assert_eq!(parts(b"x", 3), vec![&b"x"[..], b"", b""]);
        assert_eq!(parts(b"\n--8<--\n", 2), vec![&b""[..], b""]);
    }
}

/// The values a damaged or hostile file holds where a number belongs (issue "every bad input
/// refused where it is read"): non-finite, past every limit, negative, denormal.
pub const SPECIAL_F64: [f64; 9] =
    [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e308, -1e308, -1.0, -0.0, 5e-324, 1e150];
/// Sizes and counts as a damaged header gives them: negative in two's complement, the limits'
/// edges, zero.
pub const SPECIAL_SIZES: [u64; 7] =
    [0, u64::MAX, u64::MAX - 7, 1 << 31, (1 << 31) + 1, u32::MAX as u64, 1 << 62];
/// The same as text, for JSON and TOML headers: each replaces one number in place.
pub const SPECIAL_TEXT: [&str; 12] = [
    "NaN",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "-1",
    "0",
    "-0.0",
    "1e-320",
    "18446744073709551616",
    "4294967296",
    "2147483648",
];

/// A small generator from libFuzzer's seed (xorshift64*), so that a mutation is repeatable.
struct Rng(u64);

impl Rng {
    fn below(&mut self, n: usize) -> usize {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 33) as usize % n.max(1)
    }
}

/// Value mutations (a libFuzzer custom mutator's body): half the time libFuzzer's own byte
/// mutations, otherwise one of (a) an 8-byte slot of one part — aligned to the part's start,
/// where the f64 arrays of snapshots and (8-aligned) safetensors data lie — set to a
/// [`SPECIAL_F64`], (b) such a slot, or a 4-byte one, set to a [`SPECIAL_SIZES`] (safetensors'
/// header length, VTK block headers), (c) a decimal number in text replaced by a
/// [`SPECIAL_TEXT`] (JSON headers, metadata strings, TOML). `data` has room for `max_size`
/// bytes of which `size` are the input; returns the new size.
pub fn value_mutation(data: &mut [u8], size: usize, max_size: usize, seed: u32) -> usize {
    let mut rng = Rng(u64::from(seed) | 1 << 40);
    if size == 0 || size > max_size || size > data.len() || rng.below(2) == 0 {
        return libfuzzer_sys::fuzzer_mutate(data, size, max_size);
    }
    // Part starts: 0 and after each separator line.
    const SEP: &[u8] = b"\n--8<--\n";
    let mut starts = vec![0];
    starts.extend(memchr::memmem::find_iter(&data[..size], SEP).map(|i| i + SEP.len()));
    let start = starts[rng.below(starts.len())];
    let end = starts.iter().copied().find(|&s| s > start).map_or(size, |s| s - SEP.len());
    match rng.below(3) {
        0 | 1 => {
            let width = if rng.below(4) == 0 { 4 } else { 8 };
            let slots = (end - start) / width;
            if slots == 0 {
                return libfuzzer_sys::fuzzer_mutate(data, size, max_size);
            }
            let at = start + width * rng.below(slots);
            let bytes: Vec<u8> = match (width, rng.below(2)) {
                (8, 0) => SPECIAL_F64[rng.below(SPECIAL_F64.len())].to_le_bytes().to_vec(),
                (8, _) => SPECIAL_SIZES[rng.below(SPECIAL_SIZES.len())].to_le_bytes().to_vec(),
                _ => (SPECIAL_SIZES[rng.below(SPECIAL_SIZES.len())] as u32).to_le_bytes().to_vec(),
            };
            data[at..at + width].copy_from_slice(&bytes);
            size
        }
        _ => {
            // Numbers in the part: runs of digits (with a sign, point and exponent) in text.
            let text = &data[start..end];
            let mut numbers = Vec::new();
            let mut i = 0;
            while i < text.len() && numbers.len() < 4096 {
                if text[i].is_ascii_digit() {
                    let mut j = i;
                    while j < text.len() && (text[j].is_ascii_alphanumeric() || b".+-".contains(&text[j])) {
                        j += 1;
                    }
                    let from = if i > 0 && text[i - 1] == b'-' { i - 1 } else { i };
                    numbers.push((start + from, start + j));
                    i = j;
                } else {
                    i += 1;
                }
            }
            if numbers.is_empty() {
                return libfuzzer_sys::fuzzer_mutate(data, size, max_size);
            }
            let (a, b) = numbers[rng.below(numbers.len())];
            let new = SPECIAL_TEXT[rng.below(SPECIAL_TEXT.len())].as_bytes();
            let grown = size - (b - a) + new.len();
            if grown > max_size.min(data.len()) {
                return size;
            }
            data.copy_within(b..size, a + new.len());
            data[a..a + new.len()].copy_from_slice(new);
            grown
        }
    }
}
