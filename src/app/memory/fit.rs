//! Whether an estimate fits in what this process may use ([`crate::host::available`]): refuse
//! it, or run rayon's workers fewer when only their address space is in excess.

use super::MemoryEstimate;
use crate::case::CaseError;
use crate::host::{available, bytes_text, Available};

/// Refuse `estimate` of what `command` needs when it is larger than what is available. Under
/// an address-space limit whose only excess is rayon's workers (each reserving a dense kernel
/// buffer and a malloc arena), first size rayon's global pool to as many workers as fit: the
/// LATIN stages then run on fewer threads, with the same results.
pub fn ensure_fits(estimate: &MemoryEstimate, command: &str) -> Result<(), CaseError> {
    ensure_fits_in(estimate, command, available())
}

/// [`ensure_fits`] against `available`, read before the command allocated anything of its own
/// (read after, the memory it holds would count against it).
pub fn ensure_fits_in(
    estimate: &MemoryEstimate,
    command: &str,
    available: Option<Available>,
) -> Result<(), CaseError> {
    let Some(available) = available else {
        return Ok(());
    };
    let main_thread = (estimate.dense_threads - estimate.worker_threads) as u64;
    let threads = |workers: usize| available.threads_bytes(main_thread, workers);
    match workers_that_fit(
        estimate.total(),
        &available,
        main_thread,
        estimate.worker_threads,
    ) {
        Some(w) if w == estimate.worker_threads => return Ok(()),
        // Building the pool fails only when it already runs with every worker: then refuse.
        Some(w)
            if rayon::ThreadPoolBuilder::new()
                .num_threads(w)
                .build_global()
                .is_ok() =>
        {
            return Ok(())
        }
        _ => {}
    }
    // Refused even with the fewest workers: say what the threads take then.
    let fewest = estimate.worker_threads.min(1);
    let threads = match (threads(fewest), fewest) {
        (0, _) => String::new(),
        (bytes, 0) => format!(
            ", and {} of address space for the main thread's dense kernels (twice the L3 cache)",
            bytes_text(bytes)
        ),
        (bytes, _) => format!(
            ", and {} of address space for the main thread and one rayon worker (the fewest): \
             twice the L3 cache each for dense kernels, and the worker's malloc arena",
            bytes_text(bytes)
        ),
    };
    Err(CaseError::TooLarge {
        command: command.to_string(),
        estimate: format!("{estimate}{threads}"),
        available: available.to_string(),
    })
}

/// How many of `workers` rayon workers fit beside `total` bytes: all of them, else the most
/// (at least one) that do, else `None`.
fn workers_that_fit(total: u64, available: &Available, main: u64, workers: usize) -> Option<usize> {
    let fits = |w: usize| total + available.threads_bytes(main, w) <= available.bytes;
    if fits(workers) {
        return Some(workers);
    }
    (1..workers).rev().find(|&w| fits(w))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Under an address-space limit, workers are dropped until they fit, down to one.
    #[test]
    fn workers_are_as_many_as_the_address_space_allows() {
        let mb = 1 << 20;
        let limit = |bytes: u64| Available {
            bytes,
            dense_buffer: 64 * mb,
            arena: 128 * mb,
            source: String::new(),
        };
        // 100 MB + main 64 MB + w · (64 + 128) MB.
        assert_eq!(workers_that_fit(100 * mb, &limit(548 * mb), 1, 2), Some(2));
        assert_eq!(workers_that_fit(100 * mb, &limit(547 * mb), 1, 2), Some(1));
        assert_eq!(workers_that_fit(100 * mb, &limit(356 * mb), 1, 2), Some(1));
        assert_eq!(workers_that_fit(100 * mb, &limit(355 * mb), 1, 2), None);
        assert_eq!(workers_that_fit(100 * mb, &limit(164 * mb), 1, 0), Some(0));
        assert_eq!(workers_that_fit(100 * mb, &limit(163 * mb), 1, 0), None);
        // Resident-memory limits reserve nothing per thread.
        let resident = Available {
            bytes: 100 * mb,
            dense_buffer: 0,
            arena: 0,
            source: String::new(),
        };
        assert_eq!(workers_that_fit(100 * mb, &resident, 1, 64), Some(64));
    }
}
