//! Limits on what input may declare, checked before anything is allocated from it: a count
//! read from a file must fit both an absolute limit and the bytes (or lines) the file still
//! has, since every declared item takes at least some of them. A hostile header then gives an
//! error naming the count instead of an allocation of its size (which aborts the process).

/// The most items of one kind (nodes, elements, values) any reader accepts: 2³¹.
pub const MAX_COUNT: u64 = 1 << 31;

/// `count` (`what`, as the file declares it) checked: at most [`MAX_COUNT`], and at most
/// `remaining / min_size` when each item takes at least `min_size` of the `remaining` bytes or
/// lines. Returns it as a `usize`, or a sentence saying why it cannot be.
pub fn declared_count(what: &str, count: u64, remaining: usize, min_size: usize) -> Result<usize, String> {
    if count > MAX_COUNT {
        return Err(format!("{what}: {count} is over the limit of {MAX_COUNT}"));
    }
    let room = remaining as u64 / min_size.max(1) as u64;
    if count > room {
        return Err(format!(
            "{what}: {count} declared, but the rest of the file ({remaining} {}) holds at most {room}",
            if min_size == 1 { "lines" } else { "bytes" }
        ));
    }
    usize::try_from(count).map_err(|_| format!("{what}: {count} does not fit in memory"))
}

/// An empty vector with room for `n` items (`what`), reserved fallibly: a count that passed
/// [`declared_count`] but does not fit in memory is an error naming it instead of an abort.
/// (Linux overcommits, so this catches sizes the allocator refuses outright — more than the
/// address space or a `ulimit -v` allows — not pages the kernel cannot back later.)
pub fn vec_for<T>(n: usize, what: &str) -> Result<Vec<T>, String> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| {
        format!("{what}: room for {n} items of {} bytes cannot be allocated", std::mem::size_of::<T>())
    })?;
    Ok(v)
}

/// The largest magnitude a physical value read from input may have: 10¹⁵⁰. Its square is
/// 10³⁰⁰, so energies, norms and Gram matrices summed over up to 10⁸ such values stay finite;
/// a value past it (a 1e308 in a velocity) is a damaged file, not a state to simulate.
pub const MAX_MAGNITUDE: f64 = 1e150;

/// The first of `values` that is not finite or exceeds [`MAX_MAGNITUDE`], as `(index, value)`.
pub fn first_out_of_range(values: &[f64]) -> Option<(usize, f64)> {
    values.iter().position(|v| v.is_nan() || v.abs() > MAX_MAGNITUDE).map(|i| (i, values[i]))
}

/// What is wrong with a value [`first_out_of_range`] found: "NaN (not finite)", "1e308 (past
/// the limit of 1e150)".
pub fn out_of_range_reason(value: f64) -> String {
    if value.is_finite() {
        format!("{value:e} (past the limit of ±{MAX_MAGNITUDE:e})")
    } else {
        format!("{value} (not finite)")
    }
}

/// The machine's physical memory in bytes (`MemTotal` of `/proc/meminfo`); `None` where it
/// cannot be read (then checks that need it are skipped).
pub fn memory_total() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kb.checked_mul(1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_must_fit_the_limit_and_the_rest_of_the_file() {
        assert_eq!(declared_count("nodes", 10, 100, 8), Ok(10));
        assert_eq!(declared_count("nodes", 12, 100, 8), Ok(12));
        assert!(declared_count("nodes", 13, 100, 8).unwrap_err().contains("holds at most 12"));
        assert!(declared_count("nodes", 1 << 40, usize::MAX, 1).unwrap_err().contains("over the limit"));
        assert_eq!(declared_count("lines", 0, 0, 1), Ok(0));
    }

    #[test]
    fn a_reservation_past_the_address_space_is_an_error_naming_it() {
        assert!(vec_for::<u64>(1000, "nodes").expect("small").capacity() >= 1000);
        let e = vec_for::<u64>(usize::MAX / 4, "the node tags").expect_err("too large");
        assert!(e.contains("the node tags") && e.contains("cannot be allocated"), "{e}");
    }

    #[test]
    fn values_past_the_magnitude_limit_or_not_finite_are_found() {
        assert_eq!(first_out_of_range(&[0.0, -1e150, 1e150]), None);
        assert_eq!(first_out_of_range(&[0.0, 1e308, f64::NAN]), Some((1, 1e308)));
        assert!(first_out_of_range(&[f64::NAN]).is_some_and(|(i, v)| i == 0 && v.is_nan()));
        assert_eq!(first_out_of_range(&[1.0, f64::NEG_INFINITY]), Some((1, f64::NEG_INFINITY)));
        assert!(out_of_range_reason(1e308).contains("past the limit"));
        assert!(out_of_range_reason(f64::NAN).contains("not finite"));
    }
}
