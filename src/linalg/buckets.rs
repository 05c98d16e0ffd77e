//! Items grouped by bucket, each bucket in the order the items came (a stable counting sort):
//! the rows of a column-stored matrix, the holders of a shared dof.

/// `(start, items)`: bucket b's items at `items[start[b]..start[b + 1]]`, in the order `each`
/// gave them. `each` is called twice (count, then fill) and must give the same
/// `(bucket, item)` pairs, in the same order, both times.
pub fn buckets<T: Copy + Default>(
    n_buckets: usize,
    each: impl Fn(&mut dyn FnMut(usize, T)),
) -> (Vec<usize>, Vec<T>) {
    let mut start = vec![0usize; n_buckets + 1];
    each(&mut |b, _| start[b + 1] += 1);
    for b in 0..n_buckets {
        start[b + 1] += start[b];
    }
    let mut next = start[..n_buckets].to_vec();
    let mut items = vec![T::default(); start[n_buckets]];
    each(&mut |b, item| {
        items[next[b]] = item;
        next[b] += 1;
    });
    (start, items)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_land_in_their_bucket_in_the_order_given() {
        let pairs = [(2, 'a'), (0, 'b'), (2, 'c'), (1, 'd'), (0, 'e')];
        let (start, items) = buckets(4, |emit| pairs.iter().for_each(|&(b, c)| emit(b, c)));
        assert_eq!(start, vec![0, 2, 3, 5, 5]);
        assert_eq!(items, vec!['b', 'e', 'd', 'a', 'c']);
    }
}
