//! Draw lists by strategy (the seeds' "individual", "join" and "material groups"), rebuilt only
//! when the scene's draws change.

use std::collections::HashMap;

use cadr_plugin_sdk::abi::{self, CadrInstance};
use cadr_plugin_sdk::{PassFilter, Scene};

/// How draws are formed from the drawn instances.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// One draw per part, in scene order.
    Individual,
    /// One draw per part, sorted by state (geometry, material, matrix).
    Sorted,
    /// Adjacent parts of an object with equal state joined into one range.
    Join,
    /// Per object, one batch per material (and flags) with all its ranges.
    Groups,
}

/// One index range and the instance it starts at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Range {
    /// Instance id (its part binds and offsets the range).
    pub instance: u32,
    /// First index (absolute, in the pass's index buffer).
    pub first: u32,
    /// Index count.
    pub count: u32,
}

/// Ranges drawn with one parameter binding.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Batch {
    /// The instance whose parameters the batch uses.
    pub instance: u32,
    /// Its ranges, as positions in [`PassList::ranges`].
    pub ranges: std::ops::Range<usize>,
}

/// The batches of one pass.
#[derive(Clone, Debug, Default)]
pub struct PassList {
    /// Batches in recording order.
    pub batches: Vec<Batch>,
    /// Every batch's ranges.
    pub ranges: Vec<Range>,
}

fn pass_range(instance: &CadrInstance, pass: abi::CadrPassKind) -> (u32, u32) {
    if pass == abi::CADR_PASS_EDGES {
        (instance.first_wire_index, instance.wire_index_count)
    } else {
        (instance.first_index, instance.index_count)
    }
}

/// What two instances must share to be drawn with one binding of parameters.
fn state_key(instance: &CadrInstance) -> (u32, u32, u32, u32) {
    (
        instance.matrix,
        instance.material,
        instance.flags,
        instance.geometry,
    )
}

/// A batch of its own for every range.
fn one_batch_per_range(ranges: &[Range]) -> Vec<Batch> {
    ranges
        .iter()
        .enumerate()
        .map(|(i, r)| Batch {
            instance: r.instance,
            ranges: i..i + 1,
        })
        .collect()
}

/// Builds the list of `pass` with `strategy`, of the drawn instances `filter` keeps. The pick
/// pass never joins parts (each pixel must name its part): joining strategies draw it one part
/// per range and binding, in scene order.
pub fn build(
    scene: &Scene<'_>,
    (pass, filter): (abi::CadrPassKind, PassFilter),
    strategy: Strategy,
) -> PassList {
    let strategy = match strategy {
        Strategy::Join | Strategy::Groups if pass == abi::CADR_PASS_PICK => Strategy::Individual,
        other => other,
    };
    let instances = scene.instances();
    let drawn = scene.drawn_ids().filter_map(|id| {
        let instance = instances.get(id as usize)?;
        if !filter.keeps(instance.flags) {
            return None;
        }
        let (first, count) = pass_range(instance, pass);
        (count > 0).then_some(Range {
            instance: id,
            first,
            count,
        })
    });
    let mut list = PassList::default();
    match strategy {
        Strategy::Individual | Strategy::Sorted => {
            list.ranges = drawn.collect();
            if strategy == Strategy::Sorted {
                list.ranges.sort_by_key(|r| {
                    let i = &instances[r.instance as usize];
                    (i.geometry, i.material, i.matrix, r.first)
                });
            }
            list.batches = one_batch_per_range(&list.ranges);
        }
        Strategy::Join => {
            for range in drawn {
                let key = state_key(&instances[range.instance as usize]);
                if let Some(last) = list.ranges.last_mut() {
                    if state_key(&instances[last.instance as usize]) == key
                        && last.first + last.count == range.first
                    {
                        last.count += range.count;
                        continue;
                    }
                }
                list.ranges.push(range);
            }
            list.batches = one_batch_per_range(&list.ranges);
        }
        Strategy::Groups => {
            let mut groups: Vec<(u32, Vec<Range>)> = Vec::new();
            let mut index: HashMap<(u32, u32, u32, u32), usize> = HashMap::new();
            for range in drawn {
                let key = state_key(&instances[range.instance as usize]);
                let position = *index.entry(key).or_insert_with(|| {
                    groups.push((range.instance, Vec::new()));
                    groups.len() - 1
                });
                let ranges = &mut groups[position].1;
                match ranges.last_mut() {
                    Some(last) if last.first + last.count == range.first => {
                        last.count += range.count
                    }
                    _ => ranges.push(range),
                }
            }
            for (instance, ranges) in groups {
                let start = list.ranges.len();
                list.ranges.extend(ranges);
                list.batches.push(Batch {
                    instance,
                    ranges: start..list.ranges.len(),
                });
            }
        }
    }
    list
}
