//! Nested dissection of a graph whose vertices have coordinates in space: split the vertex set
//! at the median of its longest extent, take the vertices of one side that touch the other as
//! the separator, order both halves recursively, then the separator last. On grid-like graphs
//! (a tensegrity grid's node graph, the geometry coming with the structure) this is the
//! ordering whose fill grows like n log n, against AMD's larger fill on big grids.

/// Parts of at most this many vertices are not split further (kept in their given order).
/// Factor entries with 4 against 8: paper case 0.197 M against 0.202 M (flops −4 %; its
/// factorization 0.96 of the time and its solves 0.94, medians of 16 interleaved runs),
/// 64 × 64 5.17 M against 5.31 M, 128 × 128 25.5 M against 26.1 M (27.4 M with 24, 72.5 M with
/// 200), 256 × 256 121.8 M against 124.4 M (128.8 M with 16).
const LEAF: usize = 4;

/// A fill-reducing permutation of the graph `adjacency` (CSR: vertex v's neighbours are
/// `neighbours[offsets[v]..offsets[v + 1]]`, symmetric) from the vertices' `coordinates`:
/// `order[k]` is the vertex eliminated k-th.
pub fn nested_dissection(
    offsets: &[usize],
    neighbours: &[usize],
    coordinates: &[[f64; 3]],
) -> Vec<usize> {
    nested_dissection_split(offsets, neighbours, coordinates).0
}

/// Levels of the dissection tree kept for a factor split side by side ([`SplitTree`]): 16
/// subtrees, as many as threads on the largest machine measured.
const TREE_LEVELS: usize = 4;

/// The top levels of a nested dissection: the sizes of a part's two halves (in its order the
/// first half, the second, then their separator), and each half's own split.
#[derive(Debug, Clone, PartialEq)]
pub struct SplitTree {
    /// The two halves' sizes.
    pub parts: [usize; 2],
    /// Each half's split (`None`: not split, or below the levels kept).
    pub children: [Option<Box<SplitTree>>; 2],
}

impl SplitTree {
    /// The same tree in other units: a part of `k` vertices at position `p` of the order
    /// becomes `size(p, k)`.
    pub fn measured(&self, at: usize, size: &impl Fn(usize, usize) -> usize) -> SplitTree {
        let [a, b] = self.parts;
        let child = |c: &Option<Box<SplitTree>>, at: usize| {
            c.as_ref().map(|c| Box::new(c.measured(at, size)))
        };
        SplitTree {
            parts: [size(at, a), size(at + a, b)],
            children: [
                child(&self.children[0], at),
                child(&self.children[1], at + a),
            ],
        }
    }
}

/// [`nested_dissection`], and its top levels' splits: the order is the first part's vertices,
/// then the second's, then the top separator's (`None`: no split).
pub fn nested_dissection_split(
    offsets: &[usize],
    neighbours: &[usize],
    coordinates: &[[f64; 3]],
) -> (Vec<usize>, Option<SplitTree>) {
    let n = coordinates.len();
    // Per task of the top levels (task 0 the whole graph): its parts' sizes and its halves'
    // tasks, as they are split.
    let mut splits: Vec<Option<([usize; 2], [usize; 2])>> = vec![None];
    let mut order = Vec::with_capacity(n);
    // region[v]: the part v currently belongs to; a vertex is only split from vertices of its
    // own part.
    let mut region = vec![0usize; n];
    let mut next_region = 1;
    // Explicit stack: (vertices, separator to emit after them), emitted in post-order.
    enum Task {
        /// Vertices, their task in `splits` and their level (0: the whole graph).
        Split(Vec<usize>, usize, usize),
        Emit(Vec<usize>),
    }
    let mut stack = vec![Task::Split((0..n).collect(), 0, 0)];
    while let Some(next) = stack.pop() {
        let (vertices, task, level) = match next {
            Task::Emit(vertices) => {
                order.extend_from_slice(&vertices);
                continue;
            }
            Task::Split(vertices, task, level) => (vertices, task, level),
        };
        if vertices.len() <= LEAF {
            order.extend_from_slice(&vertices);
            continue;
        }
        // The longest extent (a grid's plan; a tower's height), and the median along it.
        let extent = |axis: usize| {
            let (lo, hi) = vertices
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                    (lo.min(coordinates[v][axis]), hi.max(coordinates[v][axis]))
                });
            hi - lo
        };
        let extents = [extent(0), extent(1), extent(2)];
        let axis = (0..3)
            .max_by(|&a, &b| extents[a].total_cmp(&extents[b]).then(b.cmp(&a)))
            .expect("three axes");
        let mut along: Vec<f64> = vertices.iter().map(|&v| coordinates[v][axis]).collect();
        let middle = along.len() / 2;
        let (_, &mut median, _) = along.select_nth_unstable_by(middle, f64::total_cmp);
        let (left_region, right_region) = (next_region, next_region + 1);
        next_region += 2;
        for &v in &vertices {
            region[v] = if coordinates[v][axis] < median {
                left_region
            } else {
                right_region
            };
        }
        let touches = |v: usize, other: usize, region: &[usize]| {
            neighbours[offsets[v]..offsets[v + 1]]
                .iter()
                .any(|&w| region[w] == other)
        };
        // Separator: the side's vertices that touch the other side; the smaller of the two.
        let left_boundary: Vec<usize> = vertices
            .iter()
            .copied()
            .filter(|&v| region[v] == left_region && touches(v, right_region, &region))
            .collect();
        let right_boundary: Vec<usize> = vertices
            .iter()
            .copied()
            .filter(|&v| region[v] == right_region && touches(v, left_region, &region))
            .collect();
        let separator = if left_boundary.len() <= right_boundary.len() {
            left_boundary
        } else {
            right_boundary
        };
        let separator_region = next_region;
        next_region += 1;
        for &v in &separator {
            region[v] = separator_region;
        }
        let left: Vec<usize> = vertices
            .iter()
            .copied()
            .filter(|&v| region[v] == left_region)
            .collect();
        let right: Vec<usize> = vertices
            .iter()
            .copied()
            .filter(|&v| region[v] == right_region)
            .collect();
        if left.is_empty() || right.is_empty() {
            // No split along this axis (every coordinate equal): keep the given order.
            order.extend_from_slice(&vertices);
            continue;
        }
        let mut halves = [usize::MAX; 2];
        if level < TREE_LEVELS && task != usize::MAX {
            halves = [splits.len(), splits.len() + 1];
            splits.extend([None, None]);
            splits[task] = Some(([left.len(), right.len()], halves));
        }
        // Popped in reverse: left, then right, then the separator.
        stack.push(Task::Emit(separator));
        stack.push(Task::Split(right, halves[1], level + 1));
        stack.push(Task::Split(left, halves[0], level + 1));
    }
    (order, tree(&splits, 0))
}

/// The tree of `splits` from `task` down.
fn tree(splits: &[Option<([usize; 2], [usize; 2])>], task: usize) -> Option<SplitTree> {
    let (parts, [a, b]) = splits.get(task).copied().flatten()?;
    let child = |t: usize| tree(splits, t).map(Box::new);
    Some(SplitTree {
        parts,
        children: [child(a), child(b)],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 5-point grid graph of `w × h` vertices, row by row.
    fn grid(w: usize, h: usize) -> (Vec<usize>, Vec<usize>, Vec<[f64; 3]>) {
        let mut offsets = vec![0];
        let mut neighbours = Vec::new();
        let mut coordinates = Vec::new();
        for j in 0..h {
            for i in 0..w {
                let mut push = |a: isize, b: isize| {
                    if a >= 0 && b >= 0 && (a as usize) < w && (b as usize) < h {
                        neighbours.push(b as usize * w + a as usize);
                    }
                };
                let (a, b) = (i as isize, j as isize);
                push(a - 1, b);
                push(a + 1, b);
                push(a, b - 1);
                push(a, b + 1);
                offsets.push(neighbours.len());
                coordinates.push([i as f64, j as f64, 0.0]);
            }
        }
        (offsets, neighbours, coordinates)
    }

    #[test]
    fn a_permutation_whose_top_separator_splits_the_grid() {
        let (w, h) = (40, 30);
        let (offsets, neighbours, coordinates) = grid(w, h);
        let order = nested_dissection(&offsets, &neighbours, &coordinates);
        // A permutation.
        let mut seen = vec![false; w * h];
        for &v in &order {
            assert!(!seen[v], "vertex {v} twice");
            seen[v] = true;
        }
        assert!(seen.iter().all(|&s| s));
        // The last h vertices are the first separator: one grid column (x is the longer
        // extent), which disconnects the rest.
        let last = &order[order.len() - h..];
        let column = coordinates[last[0]][0];
        assert!(
            last.iter().all(|&v| coordinates[v][0] == column),
            "{last:?}"
        );
        assert!(
            (column - (w / 2) as f64).abs() <= 1.0,
            "separator at x = {column}"
        );
    }
}
