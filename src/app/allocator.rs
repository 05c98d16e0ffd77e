//! The process's allocator policy: freed memory is kept for the next solve instead of being
//! handed back to the kernel.
//!
//! glibc returns a freed block of more than 128 KiB (raised up to 32 MiB as blocks are freed)
//! to the kernel at once, and trims the top of its heap as soon as 128 KiB of it are free. A
//! solve's factor, its workspace and its symbolic analysis are such blocks: every solve after
//! the first then touches them as new pages, and each first touch is a page fault. Set up and
//! solve the paper's case in a loop and it faults 900 times per solve, about a quarter of the
//! loop's time on this machine (100 set-ups and solves: 116 k faults and 2.2 s of CPU, against
//! 4 k and 1.6 s with the policy below). A fresh process still pays the first touch of what it
//! uses: this saves what a sweep, a benchmark or any solve after the first would pay again.

/// Blocks up to this size come from the heap, where freed memory is reused (glibc's ceiling
/// for this threshold; larger blocks are still mapped and unmapped one by one).
const MMAP_THRESHOLD: i32 = 32 << 20;
/// Free memory kept at the top of the heap before glibc gives it back to the kernel.
const TRIM_THRESHOLD: i32 = 256 << 20;

/// Apply the policy (glibc on Linux; elsewhere the system allocator is left as it is). Call it
/// once, before the first solve.
pub fn retain_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only changes two of glibc's tuning parameters; both values are in range.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD);
        libc::mallopt(libc::M_TRIM_THRESHOLD, TRIM_THRESHOLD);
    }
}

#[cfg(all(test, target_os = "linux", target_env = "gnu"))]
mod tests {
    use super::*;

    /// Minor page faults of the calling thread so far.
    fn page_faults() -> i64 {
        // SAFETY: getrusage writes one rusage struct, which is plain data.
        let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
        let status = unsafe { libc::getrusage(libc::RUSAGE_THREAD, &mut usage) };
        assert_eq!(status, 0, "getrusage");
        usage.ru_minflt
    }

    /// A solve's blocks in small: ten blocks of 1 MiB written, then all freed, round after
    /// round. With glibc's default policy each round after the first writes fresh pages
    /// (2 560 faults a round); with the policy it writes the pages the round before freed.
    #[test]
    fn freed_blocks_are_reused_without_new_page_faults() {
        retain_freed_memory();
        let round = || {
            let blocks: Vec<Vec<u8>> = (0..10).map(|k| vec![k as u8 + 1; 1 << 20]).collect();
            std::hint::black_box(&blocks);
        };
        round();
        let before = page_faults();
        for _ in 0..4 {
            round();
        }
        let faults = page_faults() - before;
        assert!(faults < 256, "{faults} page faults in 4 rounds of 10 MiB");
    }
}
