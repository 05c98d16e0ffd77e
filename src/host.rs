//! What the machine lets this process use: the memory it may still take (`/proc/meminfo`,
//! the cgroup's limit, the address-space and data-segment limits), with what an
//! address-space limit costs per thread (the dense kernels' buffers, malloc arenas).
//!
//! Knows nothing of the program above it: `case` refuses a grid whose structure alone does
//! not fit before generating it, `app::memory` a command whose estimate does not fit.

/// Below this, what the process holds is left out of the limit's wording (it is counted).
const HELD_SHOWN_BYTES: u64 = 256 << 20;

/// The address space glibc maps for a thread's malloc arena (64 MiB, mapped twice as large
/// while it is aligned).
const THREAD_ARENA_BYTES: u64 = 128 << 20;

/// The memory this process may still use, and which limit says so.
#[derive(Debug, Clone, PartialEq)]
pub struct Available {
    /// Bytes of memory the estimate may use.
    pub bytes: u64,
    /// Bytes of address space each thread running a dense kernel reserves beyond `bytes`,
    /// when the limit is one of address space (`ulimit -v`, `ulimit -d`): twice the L3 cache,
    /// which faer's gemm (`private-gemm-x86`) reserves on every such thread, with no setting.
    pub dense_buffer: u64,
    /// Bytes of address space each worker thread's malloc arena takes under such a limit:
    /// glibc's 64 MiB arena, mapped twice as large while it is aligned.
    pub arena: u64,
    /// The limit, as the user would name it.
    pub source: String,
}

/// The smallest of: `MemAvailable` of `/proc/meminfo`; the cgroup's `memory.max` less its
/// `memory.current` (v1: `memory.limit_in_bytes` less `memory.usage_in_bytes`), inactive page
/// cache left out; `RLIMIT_AS` (`ulimit -v`) less the address space in use; `RLIMIT_DATA`
/// (`ulimit -d`) less the data segment in use. The first two count what this process holds
/// already (its resident set) as available to it: an estimate is of the whole process, and a
/// case's generated grid is resident before its run is estimated (3.4 GB on 1024 × 1024
/// modules, which the estimate's structure part counts too). `None` when none can be read.
pub fn available() -> Option<Available> {
    let mut best: Option<Available> = None;
    let mut consider = |bytes: u64, address_space: bool, source: String| {
        if best.as_ref().is_none_or(|b| bytes < b.bytes) {
            best = Some(Available {
                bytes,
                dense_buffer: if address_space {
                    2 * l3_cache_bytes()
                } else {
                    0
                },
                arena: if address_space { THREAD_ARENA_BYTES } else { 0 },
                source,
            });
        }
    };
    let resident = proc_field("/proc/self/status", "VmRSS:").unwrap_or(0) << 10;
    let held = match resident >= HELD_SHOWN_BYTES {
        true => format!(", and the {} this process holds", bytes_text(resident)),
        false => String::new(),
    };
    if let Some(kb) = proc_field("/proc/meminfo", "MemAvailable:") {
        consider(
            (kb << 10) + resident,
            false,
            format!("MemAvailable {}{held}", bytes_text(kb << 10)),
        );
    }
    if let Some((max, current)) = cgroup_limit() {
        consider(
            max.saturating_sub(current.saturating_sub(resident)),
            false,
            format!(
                "cgroup memory limit {}, {} in use{held}",
                bytes_text(max),
                bytes_text(current)
            ),
        );
    }
    // A process limit leaves what the process does not use yet: (limit, its /proc field, how
    // the limit and the use are named).
    for (resource, field, limit_name, used_name) in [
        (
            libc::RLIMIT_AS,
            "VmSize:",
            "RLIMIT_AS (ulimit -v)",
            "of address space in use",
        ),
        (
            libc::RLIMIT_DATA,
            "VmData:",
            "RLIMIT_DATA (ulimit -d)",
            "in use",
        ),
    ] {
        let used = proc_field("/proc/self/status", field).unwrap_or(0) << 10;
        if let Some(limit) = rlimit(resource) {
            consider(
                limit.saturating_sub(used),
                true,
                format!(
                    "{limit_name} {}, {} {used_name}",
                    bytes_text(limit),
                    bytes_text(used)
                ),
            );
        }
    }
    best
}

/// The soft limit `resource`, bytes, when one is set. std has no `getrlimit`, hence `libc`.
fn rlimit(resource: libc::__rlimit_resource_t) -> Option<u64> {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes one `rlimit` through a valid pointer.
    let ok = unsafe { libc::getrlimit(resource, &mut limit) } == 0;
    (ok && limit.rlim_cur != libc::RLIM_INFINITY).then_some(limit.rlim_cur)
}

/// The number after `field` (kB) in a `/proc` file of `key: value kB` lines.
fn proc_field(path: &str, field: &str) -> Option<u64> {
    let text = std::fs::read_to_string(path).ok()?;
    let line = text.lines().find(|l| l.starts_with(field))?;
    line[field.len()..].split_whitespace().next()?.parse().ok()
}

/// Limits this large mean "none" (cgroup v1 writes 2^63 rounded down to a page).
const CGROUP_UNLIMITED: u64 = 1 << 62;

/// The cgroup memory limit of this process and what counts against it, when a limit is set:
/// v2 `memory.max` and `memory.current`, or v1 `memory.limit_in_bytes` and
/// `memory.usage_in_bytes`; the inactive page cache (`memory.stat`), which the kernel reclaims
/// before it fails an allocation, is not counted as used.
fn cgroup_limit() -> Option<(u64, u64)> {
    let membership = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let v2 = membership.lines().find_map(|l| l.strip_prefix("0::"));
    let v1 = membership
        .lines()
        .find_map(|l| l.split_once(":memory:").map(|(_, p)| p));
    let candidates = [
        (
            v2.map(|p| format!("/sys/fs/cgroup{p}")),
            "memory.max",
            "memory.current",
            "inactive_file",
        ),
        (
            Some("/sys/fs/cgroup".into()),
            "memory.max",
            "memory.current",
            "inactive_file",
        ),
        (
            v1.map(|p| format!("/sys/fs/cgroup/memory{p}")),
            "memory.limit_in_bytes",
            "memory.usage_in_bytes",
            "total_inactive_file",
        ),
        (
            Some("/sys/fs/cgroup/memory".into()),
            "memory.limit_in_bytes",
            "memory.usage_in_bytes",
            "total_inactive_file",
        ),
    ];
    for (dir, limit, usage, inactive) in candidates {
        let Some(dir) = dir else { continue };
        let read = |f: &str| std::fs::read_to_string(format!("{dir}/{f}")).ok();
        let Some(max) = read(limit).and_then(|m| m.trim().parse::<u64>().ok()) else {
            continue;
        };
        if max >= CGROUP_UNLIMITED {
            return None;
        }
        let used = read(usage)
            .and_then(|c| c.trim().parse::<u64>().ok())
            .unwrap_or(0);
        let reclaimable = read("memory.stat")
            .and_then(|stat| {
                stat.lines().find_map(|l| {
                    l.strip_prefix(inactive)?
                        .strip_prefix(' ')?
                        .trim()
                        .parse()
                        .ok()
                })
            })
            .unwrap_or(0);
        return Some((max, used.saturating_sub(reclaimable)));
    }
    None
}

/// The L3 cache size the dense kernels size their buffers by (`/sys`; 32 MiB when unknown).
fn l3_cache_bytes() -> u64 {
    let unknown = 32 << 20;
    let Ok(entries) = std::fs::read_dir("/sys/devices/system/cpu/cpu0/cache") else {
        return unknown;
    };
    for e in entries.flatten() {
        let read = |f: &str| std::fs::read_to_string(e.path().join(f)).ok();
        if read("level").is_some_and(|l| l.trim() == "3") {
            if let Some(size) = read("size") {
                let size = size.trim();
                let (number, unit) = size.split_at(size.len() - 1);
                let scale = match unit {
                    "K" => 1 << 10,
                    "M" => 1 << 20,
                    "G" => 1 << 30,
                    _ => return unknown,
                };
                return number.parse::<u64>().map_or(unknown, |n| n * scale);
            }
        }
    }
    unknown
}

impl Available {
    /// Address space of `main` threads and `workers` rayon workers running dense kernels.
    pub fn threads_bytes(&self, main: u64, workers: usize) -> u64 {
        self.dense_buffer * (main + workers as u64) + self.arena * workers as u64
    }
}

/// `1.23 GB (MemAvailable 1.23 GB)`: the bytes, and which limit says so.
impl std::fmt::Display for Available {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ({})", bytes_text(self.bytes), self.source)
    }
}

/// `1.23 GB` (decimal units, as `free` and `/usr/bin/time` users read them).
pub fn bytes_text(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1e9 {
        format!("{:.2} GB", b / 1e9)
    } else {
        format!("{:.0} MB", (b / 1e6).max(1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What the process holds counts as available to it: with 512 MB resident, a limit read
    /// from `MemAvailable` is that plus the resident set (within what other processes may
    /// take meanwhile), and says so.
    #[test]
    fn the_resident_set_counts_as_available() {
        let held: Vec<u8> = vec![1; 512 << 20];
        std::hint::black_box(&held);
        let Some(found) = available() else {
            return;
        };
        if !found.source.starts_with("MemAvailable") {
            return; // a cgroup or process limit is smaller here
        }
        let resident = proc_field("/proc/self/status", "VmRSS:").unwrap() << 10;
        let free = proc_field("/proc/meminfo", "MemAvailable:").unwrap() << 10;
        assert!(resident >= 512 << 20, "{resident}");
        assert!(
            found.bytes.abs_diff(free + resident) < 256 << 20,
            "{} against {free} + {resident}",
            found.bytes
        );
        assert!(
            found.source.contains("this process holds"),
            "{}",
            found.source
        );
        drop(held);
    }
}
