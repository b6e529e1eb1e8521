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
}
