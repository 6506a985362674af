//! Limits on what a file header or an operator may ask for, checked before anything is
//! allocated or started: a header's size against the file's own length, and every allocation a
//! header implies against a memory ceiling (`ROVERNAV_MAX_ALLOC_MB`, default 4096 MiB).

/// Default ceiling on one allocation a file header implies (MiB).
pub const DEFAULT_MAX_ALLOC_MB: u64 = 4096;

/// The ceiling on one allocation a file header implies (bytes): `ROVERNAV_MAX_ALLOC_MB` MiB when
/// set to a positive integer, else [`DEFAULT_MAX_ALLOC_MB`].
pub fn max_alloc_bytes() -> u64 {
    let mb = std::env::var("ROVERNAV_MAX_ALLOC_MB")
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
        .filter(|&v| v > 0)
        .unwrap_or(DEFAULT_MAX_ALLOC_MB);
    mb.saturating_mul(1 << 20)
}

/// The element count of a `dims` array (product without overflow) of `elem_bytes`-byte elements,
/// or a one-line reason: the product overflows, exceeds the memory ceiling, or needs more than
/// `available` bytes of input when given (a header promising more than the file holds).
pub fn checked_elements(dims: &[u64], elem_bytes: u64, available: Option<u64>) -> Result<usize, String> {
    let shown = dims.iter().map(u64::to_string).collect::<Vec<_>>().join(" x ");
    let count = dims
        .iter()
        .try_fold(1u64, |acc, &d| acc.checked_mul(d))
        .ok_or_else(|| format!("size {shown} overflows"))?;
    let bytes = count.checked_mul(elem_bytes.max(1)).ok_or_else(|| format!("size {shown} overflows"))?;
    if let Some(available) = available
        && bytes > available
    {
        return Err(format!("size {shown} needs {bytes} bytes but the input holds {available}"));
    }
    let ceiling = max_alloc_bytes();
    if bytes > ceiling {
        return Err(format!(
            "size {shown} needs {bytes} bytes, over the memory ceiling of {} MiB (ROVERNAV_MAX_ALLOC_MB)",
            ceiling >> 20
        ));
    }
    usize::try_from(count).map_err(|_| format!("size {shown} does not fit in memory"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wrapping_product_is_refused_not_wrapped() {
        let e = checked_elements(&[1 << 32, 1 << 32], 1, None).unwrap_err();
        assert!(e.contains("overflows"), "{e}");
    }

    #[test]
    fn a_header_larger_than_its_file_is_refused() {
        let e = checked_elements(&[1_000_000, 1_000_000], 1, Some(40)).unwrap_err();
        assert!(e.contains("holds 40"), "{e}");
        assert_eq!(checked_elements(&[3, 4], 2, Some(24)), Ok(12));
    }

    #[test]
    fn an_allocation_over_the_ceiling_is_refused() {
        let e = checked_elements(&[1 << 20, 1 << 20], 8, None).unwrap_err();
        assert!(e.contains("memory ceiling"), "{e}");
    }
}
