//! The processes a command runs on: one, or the ranks of an MPI job (`--features mpi`, started
//! by `mpirun -n P`). Rank 0 reads the case and broadcasts the bytes it read, so that the ranks
//! can never disagree on it ([`load_case`]); rank 0 alone prints and writes.
//!
//! Without the feature a command runs on one process and this module is a stand-in of size 1.

use crate::case::{self, sources, Case, CaseError};
use crate::decomposition::Exchange;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

/// The processes of this command.
pub struct Ranks {
    #[cfg(feature = "mpi")]
    world: Option<mpi::topology::SimpleCommunicator>,
    #[cfg(feature = "mpi")]
    _universe: Option<mpi::environment::Universe>,
}

impl Ranks {
    /// Join the MPI job when built with MPI (a process started without `mpirun` is a job of
    /// one); otherwise one process.
    pub fn init() -> Ranks {
        #[cfg(feature = "mpi")]
        {
            let universe = mpi::initialize();
            let world = universe.as_ref().map(|u| u.world());
            Ranks {
                world,
                _universe: universe,
            }
        }
        #[cfg(not(feature = "mpi"))]
        Ranks {}
    }

    /// This process's rank, 0 … size − 1.
    pub fn rank(&self) -> usize {
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            use mpi::traits::Communicator;
            return world.rank() as usize;
        }
        0
    }

    /// How many ranks the job has.
    pub fn size(&self) -> usize {
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            use mpi::traits::Communicator;
            return world.size() as usize;
        }
        1
    }

    /// Whether this is rank 0, the one that prints and writes.
    pub fn is_root(&self) -> bool {
        self.rank() == 0
    }

    /// Rank 0's `bytes` on every rank (the others' are ignored).
    pub fn broadcast(&self, bytes: Vec<u8>) -> Vec<u8> {
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            use mpi::traits::{Communicator, Root};
            let root = world.process_at_rank(0);
            let mut len = bytes.len() as u64;
            root.broadcast_into(&mut len);
            let mut out = if self.is_root() {
                bytes
            } else {
                vec![0u8; len as usize]
            };
            root.broadcast_into(&mut out[..]);
            return out;
        }
        bytes
    }
}

impl Ranks {
    /// Whether every rank passed the same `value` (all ranks learn the answer).
    pub fn same_on_every_rank(&self, value: u64) -> bool {
        let (low, high) = self.min_max(value);
        low == high
    }

    /// The largest `value` any rank passed (all ranks learn it).
    pub fn max(&self, value: u64) -> u64 {
        self.min_max(value).1
    }

    /// The smallest and largest `value` the ranks passed.
    fn min_max(&self, value: u64) -> (u64, u64) {
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            use mpi::collective::SystemOperation;
            use mpi::traits::CommunicatorCollectives;
            let (mut low, mut high) = (0u64, 0u64);
            world.all_reduce_into(&value, &mut low, SystemOperation::min());
            world.all_reduce_into(&value, &mut high, SystemOperation::max());
            return (low, high);
        }
        (value, value)
    }
}

/// The ranks' collective operations for a solve they share ([`Exchange`]), counting what they
/// gather. Every call goes to `MPI_COMM_WORLD` from the thread that drives the solve.
pub struct RankExchange {
    rank: usize,
    size: usize,
    /// Values this rank received from the others, over all gathers.
    received: AtomicU64,
    /// Collective calls made.
    calls: AtomicU64,
    /// Nanoseconds spent in them (waiting for the other ranks included).
    nanos: AtomicU64,
}

impl Ranks {
    /// The collective operations of these ranks, for a solve they share.
    pub fn exchange(&self) -> RankExchange {
        RankExchange {
            rank: self.rank(),
            size: self.size(),
            received: AtomicU64::new(0),
            calls: AtomicU64::new(0),
            nanos: AtomicU64::new(0),
        }
    }
}

impl RankExchange {
    /// Values (f64) this rank received from the other ranks so far.
    pub fn values_received(&self) -> u64 {
        self.received.load(Ordering::Relaxed)
    }

    /// Collective calls made so far.
    pub fn calls(&self) -> u64 {
        self.calls.load(Ordering::Relaxed)
    }

    /// Seconds spent in collective calls so far, waiting for the other ranks included.
    pub fn seconds(&self) -> f64 {
        self.nanos.load(Ordering::Relaxed) as f64 * 1e-9
    }

    /// `f`, counted as one collective call and timed.
    fn collective<T>(&self, f: impl FnOnce() -> T) -> T {
        let clock = std::time::Instant::now();
        let out = f();
        self.calls.fetch_add(1, Ordering::Relaxed);
        let nanos = u64::try_from(clock.elapsed().as_nanos()).unwrap_or(u64::MAX);
        self.nanos.fetch_add(nanos, Ordering::Relaxed);
        out
    }
}

impl Exchange for RankExchange {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.size
    }

    fn all_gather(&self, mine: &[f64]) -> Vec<f64> {
        self.collective(|| self.gather_all(mine))
    }

    fn all(&self, value: bool) -> bool {
        self.collective(|| self.all_true(value))
    }

    fn exchange_with(&self, sends: Vec<(usize, Vec<f64>)>) -> Vec<Vec<f64>> {
        self.collective(|| self.send_and_receive(&sends))
    }
}

impl RankExchange {
    fn gather_all(&self, mine: &[f64]) -> Vec<f64> {
        #[cfg(feature = "mpi")]
        if self.size > 1 {
            use mpi::datatype::PartitionMut;
            use mpi::traits::CommunicatorCollectives;
            let world = mpi::topology::SimpleCommunicator::world();
            let count = mpi::Count::try_from(mine.len())
                .expect("a rank's share of a gather fits MPI's count (2³¹ values)");
            let mut counts = vec![0 as mpi::Count; self.size];
            world.all_gather_into(&count, &mut counts[..]);
            let displacements: Vec<mpi::Count> = counts
                .iter()
                .scan(0, |next, &c| {
                    let at = *next;
                    *next += c;
                    Some(at)
                })
                .collect();
            let total: usize = counts.iter().map(|&c| c as usize).sum();
            let mut all = vec![0.0f64; total];
            {
                let mut partition =
                    PartitionMut::new(&mut all[..], &counts[..], &displacements[..]);
                world.all_gather_varcount_into(mine, &mut partition);
            }
            self.received
                .fetch_add((total - mine.len()) as u64, Ordering::Relaxed);
            return all;
        }
        mine.to_vec()
    }

    /// Each send posted at once (non-blocking), then each neighbour's message received in
    /// turn: no pair of ranks waits on the other.
    fn send_and_receive(&self, sends: &[(usize, Vec<f64>)]) -> Vec<Vec<f64>> {
        #[cfg(feature = "mpi")]
        if self.size > 1 {
            use mpi::request::WaitGuard;
            use mpi::traits::{Communicator, Destination, Source};
            let world = mpi::topology::SimpleCommunicator::world();
            let received: Vec<Vec<f64>> = mpi::request::scope(|scope| {
                let _sent: Vec<WaitGuard<'_, [f64], _>> = sends
                    .iter()
                    .map(|(rank, values)| {
                        let to = world.process_at_rank(*rank as mpi::Rank);
                        WaitGuard::from(to.immediate_send(scope, &values[..]))
                    })
                    .collect();
                sends
                    .iter()
                    .map(|(rank, _)| {
                        let from = world.process_at_rank(*rank as mpi::Rank);
                        from.receive_vec::<f64>().0
                    })
                    .collect()
            });
            let count: usize = received.iter().map(Vec::len).sum();
            self.received.fetch_add(count as u64, Ordering::Relaxed);
            return received;
        }
        sends.iter().map(|_| Vec::new()).collect()
    }

    fn all_true(&self, value: bool) -> bool {
        #[cfg(feature = "mpi")]
        if self.size > 1 {
            use mpi::collective::SystemOperation;
            use mpi::traits::CommunicatorCollectives;
            let world = mpi::topology::SimpleCommunicator::world();
            let mut every = 0i32;
            world.all_reduce_into(&i32::from(value), &mut every, SystemOperation::min());
            return every == 1;
        }
        value
    }
}

/// A digest of everything `case` holds (its settings, structure and tables as loaded): equal
/// on two processes of one build when they loaded the same case.
pub fn case_digest(case: &Case) -> u64 {
    use std::hash::{Hash, Hasher};
    // SipHash with fixed keys: the same on every process of this build.
    let mut hasher = std::hash::DefaultHasher::new();
    format!("{case:?}").hash(&mut hasher);
    hasher.finish()
}

/// The case at `path` with `overrides`, the same on every rank: rank 0 reads it (and its
/// tables) from its disk and broadcasts what it read, refusals included; the other ranks load
/// it from those bytes without touching their own disks, and so reach rank 0's case or rank
/// 0's error.
pub fn load_case(ranks: &Ranks, path: &Path, overrides: &[String]) -> Result<Case, CaseError> {
    if ranks.size() == 1 {
        return case::load_with(path, overrides);
    }
    if ranks.is_root() {
        let (case, records) = sources::load_recording(path, overrides);
        ranks.broadcast(sources::encode(&records));
        case
    } else {
        let bytes = ranks.broadcast(Vec::new());
        let records = sources::decode(&bytes).unwrap_or_default();
        sources::load_replaying(path, overrides, records)
    }
}
