//! Work spread over the machine's cores: scoped threads, no pool to keep.

/// `work` applied to every item on up to one thread per core, the results in the items' order.
/// Each thread takes the next item not yet taken, so that items of uneven work (geometries of
/// every size, images) keep every core busy to the end. A panic in `work` is resumed on the
/// caller's thread (and reported to the caller's [`crate::panic_boundary`], if it runs inside
/// one).
pub fn map<T: Sync, R: Send>(items: &[T], work: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let threads = threads_for(items.len());
    if threads == 1 {
        return items.iter().map(work).collect();
    }
    let next = std::sync::atomic::AtomicUsize::new(0);
    let (next, work) = (&next, &work);
    let boundary = &crate::panic_boundary::inherit();
    let made: Vec<Vec<(usize, R)>> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                scope.spawn(move || {
                    let _inside = boundary.enter();
                    let mut made = Vec::new();
                    loop {
                        let index = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(item) = items.get(index) else {
                            return made;
                        };
                        made.push((index, work(item)));
                    }
                })
            })
            .collect();
        workers
            .into_iter()
            .map(|worker| {
                worker
                    .join()
                    .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
            })
            .collect()
    });
    let mut in_order: Vec<Option<R>> = std::iter::repeat_with(|| None).take(items.len()).collect();
    for (index, result) in made.into_iter().flatten() {
        in_order[index] = Some(result);
    }
    // Every item was taken once: no slot is left empty.
    in_order.into_iter().flatten().collect()
}

/// `work` applied to every item, mutably, on up to one thread per core (contiguous chunks of
/// items). A panic in `work` is resumed on the caller's thread (and reported to the caller's
/// [`crate::panic_boundary`], if it runs inside one).
pub fn for_each_mut<T: Send>(items: &mut [T], work: impl Fn(&mut T) + Sync) {
    let threads = threads_for(items.len());
    if threads == 1 {
        items.iter_mut().for_each(work);
        return;
    }
    let chunk = items.len().div_ceil(threads);
    let boundary = crate::panic_boundary::inherit();
    std::thread::scope(|scope| {
        let workers: Vec<_> = items
            .chunks_mut(chunk)
            .map(|chunk| {
                scope.spawn(|| {
                    let _inside = boundary.enter();
                    chunk.iter_mut().for_each(&work)
                })
            })
            .collect();
        for worker in workers {
            if let Err(panic) = worker.join() {
                std::panic::resume_unwind(panic);
            }
        }
    });
}

/// Threads for `items` items: one per core, at most one per item, at least one.
fn threads_for(items: usize) -> usize {
    std::thread::available_parallelism()
        .map_or(1, usize::from)
        .min(items)
        .max(1)
}

/// A vector of `len` items, item `i` made by `make(i, tally)`, on up to one thread per core
/// (one thread below `min_per_thread` items per thread). Each thread makes a contiguous chunk
/// of items, starting at a multiple of `align`, in order, with a tally of its own (from
/// `A::default()`); the tallies come back in the chunks' order. Each item is written once,
/// where it lies: fresh memory is first touched by all threads, which matters where a page's
/// first write costs far more than the item (a VM that backs memory on demand).
pub fn collect_indexed<T: Send, A: Default + Send>(
    len: usize,
    (align, min_per_thread): (usize, usize),
    make: impl Fn(usize, &mut A) -> T + Sync,
) -> (Vec<T>, Vec<A>) {
    let threads = threads_for(len / min_per_thread.max(1));
    let align = align.max(1);
    let chunk = len.div_ceil(threads).div_ceil(align).max(1) * align;
    let mut items: Vec<T> = Vec::with_capacity(len);
    let make = &make;
    let boundary = &crate::panic_boundary::inherit();
    let tallies = std::thread::scope(|scope| {
        let workers: Vec<_> = items.spare_capacity_mut()[..len]
            .chunks_mut(chunk)
            .enumerate()
            .map(|(index, slots)| {
                let mut fill = move || {
                    let _inside = boundary.enter();
                    let mut tally = A::default();
                    let first = index * chunk;
                    for (offset, slot) in slots.iter_mut().enumerate() {
                        slot.write(make(first + offset, &mut tally));
                    }
                    tally
                };
                if threads == 1 {
                    Ok(fill())
                } else {
                    Err(scope.spawn(fill))
                }
            })
            .collect();
        workers
            .into_iter()
            .map(|worker| match worker {
                Ok(tally) => tally,
                Err(spawned) => spawned
                    .join()
                    .unwrap_or_else(|panic| std::panic::resume_unwind(panic)),
            })
            .collect()
    });
    // SAFETY: the chunks cover slots 0..len and every slot of a chunk was written (a panic in
    // `make` was resumed above, before this line, leaving the vector empty).
    unsafe { items.set_len(len) };
    (items, tallies)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.
mod tests {
    use super::*;

    #[test]
    fn a_panic_on_a_parallel_worker_is_reported_to_the_boundary_that_started_it() {
        let caught = crate::panic_boundary::catch(|| {
            map(&(0..64).collect::<Vec<u32>>(), |&i| {
                assert!(i != 40, "item {i} is bad");
                i
            })
        })
        .unwrap_err();
        assert_eq!(caught.message, "item 40 is bad");
        assert!(
            caught
                .location
                .as_deref()
                .is_some_and(|l| l.starts_with(file!())),
            "{caught}"
        );
    }

    #[test]
    fn map_makes_every_item_once_in_order_whatever_its_work() {
        for len in [0_u64, 1, 2, 3, 17, 1000] {
            let items: Vec<u64> = (0..len).collect();
            let made = map(&items, |&i| {
                // Uneven work: the later items take longer.
                std::hint::black_box((0..i * 100).map(|k| k % 7).sum::<u64>());
                i
            });
            assert_eq!(made, items);
        }
    }

    #[test]
    fn collect_indexed_makes_every_item_once_in_order_with_aligned_tallies() {
        for (len, align) in [(0, 64), (1, 64), (1000, 64), (100_003, 64), (7, 1)] {
            let (items, tallies) = collect_indexed(len, (align, 1), |i, tally: &mut Vec<usize>| {
                tally.push(i);
                i * 3
            });
            assert_eq!(items, (0..len).map(|i| i * 3).collect::<Vec<_>>());
            let seen: Vec<usize> = tallies.iter().flatten().copied().collect();
            assert_eq!(seen, (0..len).collect::<Vec<_>>());
            for tally in &tallies {
                assert_eq!(tally.first().map_or(0, |first| first % align), 0);
            }
        }
    }
}
