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
}
