//! A solve shared by ranks exchanging with their neighbours point to point, on threads standing in for MPI ranks.

use super::*;
use crate::model::Model;
use crate::solvers::latin::{Latin, LatinSettings, LinkShare, RankLayout, SearchPolicy};
use crate::solvers::Solver;
use crate::structure::{GridSpec, LoadPattern, Structure};
use std::collections::{HashMap, VecDeque};
use std::sync::{Barrier, Condvar, Mutex};

/// Messages from one rank to another, first in first out, by (from, to).
type Mailboxes = HashMap<(usize, usize), VecDeque<Vec<f64>>>;

/// Ranks as threads of one process: the collectives meet at a barrier, the point-to-point
/// messages wait in mailboxes (first in, first out per pair of ranks, as MPI's are).
struct Hub {
    size: usize,
    barrier: Barrier,
    slots: Mutex<Vec<Vec<f64>>>,
    mail: Mutex<Mailboxes>,
    arrived: Condvar,
}

struct ThreadRank<'h> {
    hub: &'h Hub,
    rank: usize,
}

impl Exchange for ThreadRank<'_> {
    fn rank(&self) -> usize {
        self.rank
    }
    fn size(&self) -> usize {
        self.hub.size
    }
    fn all_gather(&self, mine: &[f64]) -> Vec<f64> {
        self.hub.slots.lock().unwrap()[self.rank] = mine.to_vec();
        self.hub.barrier.wait();
        let all = self.hub.slots.lock().unwrap().concat();
        self.hub.barrier.wait();
        all
    }
    fn all(&self, value: bool) -> bool {
        self.all_gather(&[f64::from(u8::from(value))])
            .iter()
            .all(|&v| v == 1.0)
    }
    fn exchange_with(&self, sends: Vec<(usize, Vec<f64>)>) -> Vec<Vec<f64>> {
        let mut mail = self.hub.mail.lock().unwrap();
        let from: Vec<usize> = sends.iter().map(|(rank, _)| *rank).collect();
        for (to, values) in sends {
            mail.entry((self.rank, to)).or_default().push_back(values);
        }
        self.hub.arrived.notify_all();
        let mut received = Vec::with_capacity(from.len());
        for q in from {
            loop {
                if let Some(values) = mail.get_mut(&(q, self.rank)).and_then(|m| m.pop_front()) {
                    received.push(values);
                    break;
                }
                mail = self.hub.arrived.wait(mail).unwrap();
            }
        }
        received
    }
}

fn grid(n: usize) -> Model {
    let spec = GridSpec {
        modules: [n, n],
        ..GridSpec::default()
    };
    Model::linear(Structure::grid(&spec, &LoadPattern::default()))
}

/// The iteration count, the rebuilds, the status and the iterate's displacements and
/// tensions of a
/// solve at `alpha` on `ranks` thread-ranks (rank 0's view: every rank's must agree).
fn solve_on(
    s: &Model,
    settings: &LatinSettings,
    alpha: f64,
    ranks: usize,
) -> (usize, usize, String, Vec<f64>, Vec<f64>) {
    solve_sharing(s, settings, alpha, ranks, false).0
}

/// [`solve_on`], each rank keeping the whole structure or (`share`) only its
/// substructures' links ([`LinkShare`]); with the answer's slack flags, and the links each
/// rank kept.
#[allow(clippy::type_complexity)]
fn solve_sharing(
    s: &Model,
    settings: &LatinSettings,
    alpha: f64,
    ranks: usize,
    share: bool,
) -> (
    (usize, usize, String, Vec<f64>, Vec<f64>),
    Vec<bool>,
    Vec<usize>,
) {
    let load: Vec<f64> = s.structure.unit_load.iter().map(|f| alpha * f).collect();
    let hub = Hub {
        size: ranks,
        barrier: Barrier::new(ranks),
        slots: Mutex::new(vec![Vec::new(); ranks]),
        mail: Mutex::new(HashMap::new()),
        arrived: Condvar::new(),
    };
    let results: Vec<_> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..ranks)
            .map(|rank| {
                let (hub, load) = (&hub, &load);
                // Each rank its own thread pool, as each MPI rank is a process of its
                // own (a rank waiting for the others inside a parallel section must not
                // hold a worker another rank needs).
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(1)
                    .build()
                    .unwrap();
                scope.spawn(move || {
                    pool.install(|| {
                        let exchange = ThreadRank { hub, rank };
                        let kept = share
                            .then(|| LinkShare::new(s, settings, rank, ranks).unwrap().unwrap());
                        let mut latin = match &kept {
                            Some((kept, share)) => {
                                Latin::on_share(kept, share, *settings, &exchange)
                            }
                            None => Latin::on_ranks(s, *settings, &exchange),
                        }
                        .unwrap();
                        let mut state = latin.init(load);
                        let status = loop {
                            let progress = latin.progress(&state);
                            if let Some(stop) = progress.stop {
                                break format!("{stop:?}");
                            }
                            if progress.iteration >= latin.max_iterations() {
                                break "MaxIterations".to_string();
                            }
                            latin.next_iter(&mut state);
                        };
                        let eq = latin.iterate(&state);
                        let links = latin.structure().links.len();
                        (
                            (
                                state.iteration,
                                state.rebuilds,
                                status,
                                eq.displacements,
                                eq.tensions,
                            ),
                            eq.slack,
                            links,
                        )
                    })
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for (r, other) in results.iter().enumerate().skip(1) {
        let (a, b) = (&other.0, &results[0].0);
        assert_eq!((a.0, a.1, &a.2), (b.0, b.1, &b.2), "rank {r} disagrees");
        for (what, x, y) in [("U", &a.3, &b.3), ("tensions", &a.4, &b.4)] {
            let first = x
                .iter()
                .zip(y)
                .position(|(p, q)| p.to_bits() != q.to_bits());
            assert!(
                first.is_none(),
                "rank {r}: {what} differ first at {first:?}"
            );
        }
        assert!(other.1 == results[0].1, "rank {r}: the slack sets differ");
    }
    let kept = results.iter().map(|r| r.2).collect();
    let (answer, slack, _) = results.into_iter().next().unwrap();
    (answer, slack, kept)
}

/// Ranks that keep only their substructures' links solve as one process holding the whole
/// structure, bit for bit, slack set included: the paper's grid at α = 2.4 in 4 × 4 and
/// 3 × 5 substructures on 2 and 3 ranks, each rank keeping its share of the links and no
/// more (every link on one rank).
#[test]
fn ranks_keeping_their_links_alone_solve_as_one_process() {
    let s = grid(16);
    for subdomains in [[4, 4], [3, 5]] {
        let settings = LatinSettings {
            subdomains,
            ..LatinSettings::default()
        };
        let (one, one_slack, _) = solve_sharing(&s, &settings, 2.4, 1, false);
        assert_eq!(one.2, "Converged");
        let slack = one_slack.iter().filter(|&&x| x).count();
        assert!(slack > 307, "{subdomains:?}: {slack} slack");
        // The answer's slack set is the shared classification's.
        let whole = crate::solvers::Equilibrium::classified(&s, one.3.clone(), one.4.clone());
        assert_eq!(whole.slack, one_slack);
        assert_eq!(whole.tensions, one.4);
        for ranks in [2, 3] {
            let (shared, shared_slack, kept) = solve_sharing(&s, &settings, 2.4, ranks, true);
            assert_eq!(
                (shared.0, shared.1, &shared.2),
                (one.0, one.1, &one.2),
                "{subdomains:?} on {ranks} ranks"
            );
            assert!(
                shared == one && shared_slack == one_slack,
                "{subdomains:?} on {ranks} ranks: the answers differ"
            );
            assert_eq!(kept.iter().sum::<usize>(), s.structure.links.len());
            assert!(kept
                .iter()
                .all(|&k| k < s.structure.links.len() / ranks + s.structure.links.len() / 10));
        }
    }
    // Status-following l reads every cable at each iteration: no share is made.
    let status = LatinSettings {
        policy: SearchPolicy::Status,
        ..LatinSettings::default()
    };
    assert!(LinkShare::new(&s, &status, 0, 2).unwrap().is_none());
}

/// On 2 and 3 ranks the solve is the one-process solve bit for bit, with s exchanged
/// point to point (inexact Newton status steps, the default) and
/// gathered whole at each iteration (status-following l): the paper's grid at α = 2.4 of
/// its default load, in 4 × 4 and 3 × 5 substructures.
#[test]
fn ranks_exchanging_point_to_point_solve_as_one_process() {
    let s = grid(16);
    for (subdomains, policy) in [
        ([4, 4], SearchPolicy::Newton),
        ([3, 5], SearchPolicy::Newton),
        ([4, 4], SearchPolicy::Status),
    ] {
        let settings = LatinSettings {
            subdomains,
            policy,
            ..LatinSettings::default()
        };
        let one = solve_on(&s, &settings, 2.4, 1);
        assert_eq!(one.2, "Converged", "{subdomains:?} {policy:?}");
        // The status matters: over a tenth of the cables slack (820 of 3072), and the
        // operators are rebuilt for it (each rank its own substructures').
        let slack = one.4.iter().zip(&s.structure.links);
        let slack = slack.filter(|(t, l)| l.unilateral && **t == 0.0);
        assert!(slack.count() > 307, "{subdomains:?} {policy:?}");
        assert!(one.1 > 0, "{subdomains:?} {policy:?}: no rebuild");
        for ranks in [2, 3] {
            let shared = solve_on(&s, &settings, 2.4, ranks);
            assert!(
                shared == one,
                "{subdomains:?} {policy:?} on {ranks} ranks: {} / {} iterations, {} / {}",
                shared.0,
                one.0,
                shared.2,
                one.2
            );
        }
    }
}

/// With soft interface modes in the macro bases (`soft_modes`), ranks that share the solve
/// (each taking its own substructures' modes, gathered on every rank) solve as one process
/// bit for bit, keeping the whole structure or their links alone: the paper's grid at
/// α = 2.4 in 4 × 4 substructures on 2 and 3 ranks; and the modes do change the solve.
#[test]
fn ranks_with_soft_interface_modes_solve_as_one_process() {
    let s = grid(16);
    let settings = LatinSettings {
        subdomains: [4, 4],
        soft_modes: Some(0.3),
        ..LatinSettings::default()
    };
    let (one, _, _) = solve_sharing(&s, &settings, 2.4, 1, false);
    assert_eq!(one.2, "Converged");
    assert!(one.1 > 0, "no rebuild: the modes were taken at set-up only");
    let plain = LatinSettings {
        soft_modes: None,
        ..settings
    };
    assert!(
        solve_on(&s, &plain, 2.4, 1) != one,
        "the soft modes changed nothing"
    );
    for ranks in [2, 3] {
        for share in [false, true] {
            let (shared, _, _) = solve_sharing(&s, &settings, 2.4, ranks, share);
            assert!(
                shared == one,
                "{ranks} ranks (links kept alone: {share}): {} / {} iterations",
                shared.0,
                one.0
            );
        }
    }
}

/// What one rank sends another is what that rank expects, and covers what it reads: every
/// interface between them (both sides) and every dof its substructures share with the
/// other's (each holder on the other rank).
#[test]
fn each_pair_of_ranks_agrees_on_what_passes_and_it_covers_the_shared_dofs() {
    let s = grid(12);
    for (subdomains, ranks) in [([4, 4], 3), ([3, 5], 4), ([6, 2], 5)] {
        let settings = LatinSettings {
            subdomains,
            ..LatinSettings::default()
        };
        let latin = Latin::new(&s, settings).unwrap();
        let (subs, own) = (&latin.operators.substructures, latin.ranks.dof_ownership());
        let plans: Vec<NeighbourPlan> = (0..ranks)
            .map(|r| NeighbourPlan::new(subs, &latin.interfaces.list, own, r, ranks))
            .collect();
        for (p, plan) in plans.iter().enumerate() {
            for nb in &plan.neighbours {
                let back = plans[nb.rank].neighbours.iter().find(|b| b.rank == p);
                let back = back.expect("the neighbour relation is symmetric");
                assert_eq!(nb.send, back.receive, "{subdomains:?} {p} → {}", nb.rank);
                assert_eq!(nb.receive, back.send, "{subdomains:?} {} → {p}", nb.rank);
            }
            // Every dof a held substructure shares, with a holder q on another rank:
            // received from q for that holder.
            let held = block(p, ranks, subs.len());
            let holders = |d: usize| -> Vec<usize> {
                (0..subs.len())
                    .filter(|&e| subs[e].dof_global.contains(&d))
                    .collect()
            };
            // Whether this rank receives of substructure `sub` an item `what` accepts.
            let receives = |sub: usize, what: &dyn Fn(&Item) -> bool| {
                let mut items = plan.neighbours.iter().flat_map(|nb| &nb.receive);
                items.any(|item| item.sub == sub && what(item))
            };
            let mut expected = 0;
            for e in held.clone() {
                for &k in &own.shared_local[e] {
                    let d = subs[e].dof_global[k as usize];
                    for f in holders(d).into_iter().filter(|f| !held.contains(f)) {
                        expected += 1;
                        let found = receives(f, &|item| {
                            item.shared
                                .iter()
                                .any(|&(_, j)| subs[f].dof_global[j as usize] == d)
                        });
                        assert!(found, "{subdomains:?} rank {p}: dof {d} of {f}");
                    }
                }
                for side in &subs[e].sides {
                    let other =
                        latin.interfaces.list[side.interface].topology.sides[1 - side.which];
                    if !held.contains(&other) {
                        let found = receives(other, &|item| {
                            item.sides
                                .iter()
                                .any(|&slot| subs[other].sides[slot].interface == side.interface)
                        });
                        assert!(
                            found,
                            "{subdomains:?} rank {p}: interface {}",
                            side.interface
                        );
                    }
                }
            }
            assert!(expected > 0 || plan.neighbours.is_empty());
            // Neighbours are the ranks it shares something with, increasing, itself not;
            // `check`'s layout counts them and what passes from the partition alone.
            let ranks_of = plan.ranks();
            assert!(ranks_of.windows(2).all(|w| w[0] < w[1]) && !ranks_of.contains(&p));
            let layout = RankLayout::new(&s.structure, &latin.settings, ranks);
            assert_eq!(
                layout.ranks[p].neighbours, ranks_of,
                "{subdomains:?} rank {p}"
            );
            assert_eq!(
                layout.ranks[p].values_sent,
                plan.values_sent(subs),
                "{subdomains:?} rank {p}"
            );
        }
    }
}
