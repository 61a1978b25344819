//! Sparse uploads (seed 000): the GPU scene's arrays (matrices, materials, instance records,
//! cull entries, local matrices) change a few items at a time. Each frame the changed items of every array are gathered on the
//! CPU into one compact buffer, each item behind its slot, and `scatter.comp` moves them into
//! place on the GPU: the bytes uploaded are those of the changed items. An array that was
//! (re)created is uploaded whole instead.

use std::sync::Arc;

use crate::commands_key::mix;
use crate::error::RenderResult;
use crate::vk::raw as vk;

use super::compute::{ScatterParameters, ScenePipelines};
use super::geometry::usage;
use super::hierarchy::MOVED_ROOT_MARK;
use crate::vk::{record_dispatch, Buffer, DescriptorSets, Device, MemoryLocation};

/// One array of the GPU scene: fixed-size items in a device buffer, following a CPU copy.
pub(super) struct GpuArray {
    pub(super) buffer: Buffer,
    name: &'static str,
    item_bytes: usize,
    capacity: usize,
    /// Slots changed since the last upload.
    pending: Vec<u32>,
    /// The whole array must be uploaded (it was created or grown).
    whole: bool,
}

impl GpuArray {
    /// An empty array of `item_bytes`-byte items (a multiple of 4).
    pub(super) fn new(
        device: &Arc<Device>,
        name: &'static str,
        item_bytes: usize,
    ) -> RenderResult<Self> {
        Ok(Self {
            buffer: Buffer::new(
                device,
                name,
                64,
                usage(device, vk::BufferUsageFlags::empty()),
                MemoryLocation::GpuOnly,
            )?,
            name,
            item_bytes,
            capacity: 0,
            pending: Vec::new(),
            whole: true,
        })
    }

    /// Makes room for `count` items; a new buffer is uploaded whole. True when the buffer was
    /// replaced. The first buffer holds `count` exactly (a loaded scene's arrays are as large
    /// as they will be); a growing array gets half as much again as it had, so a scene built
    /// part by part reallocates a logarithmic number of times.
    pub(super) fn reserve(&mut self, device: &Arc<Device>, count: usize) -> RenderResult<bool> {
        if count <= self.capacity && self.capacity > 0 {
            return Ok(false);
        }
        let grown = self.capacity + self.capacity / 2;
        let capacity = count.max(grown).max(64);
        self.buffer = Buffer::new(
            device,
            self.name,
            (capacity * self.item_bytes) as u64,
            usage(device, vk::BufferUsageFlags::empty()),
            MemoryLocation::GpuOnly,
        )?;
        self.capacity = capacity;
        self.whole = true;
        Ok(true)
    }

    /// Queues slot `slot` for the next upload.
    pub(super) fn queue(&mut self, slot: u32) {
        if !self.whole {
            self.pending.push(slot);
        }
    }

    /// Queues slot `slot` with its slot word marked for a later pass (see
    /// [`super::hierarchy::MOVED_ROOT_MARK`]); queued both ways, it is uploaded once, marked.
    pub(super) fn queue_marked(&mut self, slot: u32) {
        if !self.whole {
            self.pending.push(slot | MOVED_ROOT_MARK);
        }
    }

    /// Whether anything goes up with the next upload.
    pub(super) fn has_pending(&self) -> bool {
        self.whole || !self.pending.is_empty()
    }

    /// Whether the whole array goes up with the next upload.
    pub(super) fn is_whole(&self) -> bool {
        self.whole
    }

    /// Queues the whole array for the next upload.
    pub(super) fn queue_all(&mut self) {
        self.whole = true;
        self.pending.clear();
    }
}

/// What one upload wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UploadStats {
    /// Matrices uploaded.
    pub matrices: u64,
    /// Materials uploaded.
    pub materials: u64,
    /// Instance records uploaded.
    pub records: u64,
    /// Bytes of geometry written (arenas laid out, or geometries replaced in place).
    pub geometry_bytes: u64,
    /// Bytes of texels written (with their mip levels): every texture with the texture array,
    /// only new or changed ones with bindless textures.
    pub texture_bytes: u64,
    /// Every byte sent to the GPU: geometry, whole arrays, and the compact updates with their
    /// slots.
    pub bytes: u64,
}

/// How many arrays the GPU scene keeps: matrices, materials, material textures, instance
/// records, cull entries, part boxes, local matrices.
pub(super) const ARRAYS: usize = 7;

/// The compact update buffer and the descriptor sets that point the scatter pipeline at it and
/// at each array.
#[derive(Default)]
pub(super) struct SparseUploader {
    updates: Option<Buffer>,
    sets: Option<DescriptorSets>,
    /// The serials of the buffers the sets were written for (updates, then each array).
    written: [u64; ARRAYS + 1],
    /// Counts the writes of the sets (a recording that uses them is stale after one).
    sets_generation: u64,
    /// The compact updates of a frame, kept to be refilled without allocating.
    gathered: Vec<u8>,
    /// The last gather's scatter dispatches: per array with changed items, its index, first
    /// word in the update buffer and item count.
    dispatches: Vec<(usize, u32, u32)>,
    /// The item size of each array, in words, at the last gather.
    item_words: [u32; ARRAYS],
    /// Identifies the last gather's commands: its dispatches, the slots they write (not the
    /// items) and the sets they use.
    commands_key: u64,
}

/// An array with a function that writes the bytes of its item at a slot (exactly the array's
/// item size).
pub(super) type ArrayItems<'a> = (&'a mut GpuArray, &'a (dyn Fn(u32, &mut [u8]) + Sync));

/// Uploads every item of `array`, made by `item` straight into the buffer or its staging
/// chunks (no host copy of the whole array), on a thread per core; returns the bytes sent.
fn upload_whole(array: &mut GpuArray, item: &(dyn Fn(u32, &mut [u8]) + Sync)) -> RenderResult<u64> {
    let item_bytes = array.item_bytes;
    let size = (array.capacity * item_bytes) as u64;
    array.buffer.upload_with(0, size, |start, chunk| {
        let start = start as usize;
        // The first item starting in the chunk.
        let first = start.div_ceil(item_bytes);
        // The bytes before it: the rest of an item cut by the chunk's start.
        let head = (first * item_bytes - start).min(chunk.len());
        let mut straddling = vec![0u8; item_bytes];
        if head > 0 {
            item(first as u32 - 1, &mut straddling);
            let cut = start - (first - 1) * item_bytes;
            chunk[..head].copy_from_slice(&straddling[cut..cut + head]);
        }
        let whole_items = (chunk.len() - head) / item_bytes;
        let mut items = chunk[head..].chunks_exact_mut(item_bytes);
        for (slot, out) in (first..).zip(&mut items) {
            item(slot as u32, out);
        }
        // An item cut by the chunk's end: its head.
        let tail = items.into_remainder();
        if !tail.is_empty() {
            item((first + whole_items) as u32, &mut straddling);
            let length = tail.len();
            tail.copy_from_slice(&straddling[..length]);
        }
    })?;
    Ok(size)
}

impl SparseUploader {
    /// Gathers what changed in `arrays` on the host: whole arrays uploaded through a staging
    /// copy, changed items gathered into the update buffer (written now) for the scatter
    /// that [`SparseUploader::record`] records. Returns the items uploaded per array, where
    /// each array's items start in the update buffer (in words; see
    /// [`SparseUploader::updates`]) and the bytes sent.
    pub(super) fn gather(
        &mut self,
        device: &Arc<Device>,
        pipelines: &ScenePipelines,
        mut arrays: [ArrayItems<'_>; ARRAYS],
    ) -> RenderResult<([u64; ARRAYS], [u32; ARRAYS], u64)> {
        let mut counts = [0u64; ARRAYS];
        let mut first_words = [0u32; ARRAYS];
        let mut bytes = 0u64;
        let mut gathered = std::mem::take(&mut self.gathered);
        gathered.clear();
        self.dispatches.clear();
        let mut key = 0u64;
        for (index, (array, item)) in arrays.iter_mut().enumerate() {
            self.item_words[index] = (array.item_bytes / 4) as u32;
            if array.whole {
                bytes += upload_whole(array, *item)?;
                counts[index] = array.capacity as u64;
            } else if !array.pending.is_empty() {
                let first_word = (gathered.len() / 4) as u32;
                first_words[index] = first_word;
                array
                    .pending
                    .sort_unstable_by_key(|word| word & !MOVED_ROOT_MARK);
                // Once per slot, keeping a mark.
                array.pending.dedup_by(|later, kept| {
                    let same = *later & !MOVED_ROOT_MARK == *kept & !MOVED_ROOT_MARK;
                    if same {
                        *kept |= *later & MOVED_ROOT_MARK;
                    }
                    same
                });
                let item_bytes = array.item_bytes;
                for &word in &array.pending {
                    key = mix(key, u64::from(word));
                    gathered.extend_from_slice(&word.to_le_bytes());
                    let at = gathered.len();
                    gathered.resize(at + item_bytes, 0);
                    item(word & !MOVED_ROOT_MARK, &mut gathered[at..]);
                }
                counts[index] = array.pending.len() as u64;
                self.dispatches
                    .push((index, first_word, array.pending.len() as u32));
            }
        }
        for (array, _) in arrays.iter_mut() {
            array.whole = false;
            array.pending.clear();
        }
        let written = self.write_updates(device, pipelines, &arrays, &gathered);
        self.gathered = gathered;
        written?;
        for &(index, first_word, item_count) in &self.dispatches {
            key = mix(key, (index as u64) << 32 | u64::from(first_word));
            key = mix(key, u64::from(item_count));
        }
        self.commands_key = mix(key, self.sets_generation);
        Ok((counts, first_words, bytes + self.gathered.len() as u64))
    }

    /// What the commands [`SparseUploader::record`] records for the last gather depend on:
    /// equal keys record equal commands (the items they move may differ).
    pub(super) fn commands_key(&self) -> u64 {
        self.commands_key
    }

    /// The buffer the last upload's compact items went through, if any.
    pub(super) fn updates(&self) -> Option<&Buffer> {
        self.updates.as_ref()
    }

    /// Writes `gathered` into the update buffer (grown if need be) and points the sets at it
    /// and the arrays.
    fn write_updates(
        &mut self,
        device: &Arc<Device>,
        pipelines: &ScenePipelines,
        arrays: &[ArrayItems<'_>; ARRAYS],
        gathered: &[u8],
    ) -> RenderResult<()> {
        if gathered.is_empty() {
            return Ok(());
        }
        let needed = gathered.len() as u64;
        if self.updates.as_ref().is_none_or(|u| u.size() < needed) {
            self.updates = Some(Buffer::new(
                device,
                "scene updates",
                needed.next_power_of_two().max(256),
                vk::BufferUsageFlags::STORAGE_BUFFER,
                MemoryLocation::CpuToGpu,
            )?);
        }
        let Some(updates) = self.updates.as_mut() else {
            return Ok(());
        };
        updates.write(0, gathered)?;
        let mut targets = [updates.raw(); ARRAYS + 1];
        let mut serials = [updates.serial(); ARRAYS + 1];
        for ((target, serial), (array, _)) in
            targets[1..].iter_mut().zip(&mut serials[1..]).zip(arrays)
        {
            *target = array.buffer.raw();
            *serial = array.buffer.serial();
        }
        if self.sets.is_none() {
            let layouts = [pipelines.scatter_set_layout(); ARRAYS];
            self.sets = Some(DescriptorSets::new(device, "scatter", &layouts)?);
            self.sets_generation += 1;
        }
        let Some(sets) = &self.sets else {
            return Ok(());
        };
        if self.written != serials {
            let ssbo = vk::DescriptorType::STORAGE_BUFFER;
            for set in 0..ARRAYS {
                sets.write_buffer(set, 0, ssbo, targets[0], vk::WHOLE_SIZE);
                sets.write_buffer(set, 1, ssbo, targets[set + 1], vk::WHOLE_SIZE);
            }
            self.written = serials;
            self.sets_generation += 1;
        }
        Ok(())
    }

    /// Records the last gather's scatter, one dispatch per array with changed items (before
    /// the frame's pass; the frame's barrier makes the writes visible to drawing).
    pub(super) fn record(
        &self,
        device: &Device,
        pipelines: &ScenePipelines,
        command_buffer: vk::CommandBuffer,
    ) -> RenderResult<()> {
        let Some(sets) = &self.sets else {
            return Ok(());
        };
        if self.dispatches.is_empty() {
            return Ok(());
        }
        let scatter = pipelines.scatter()?;
        for &(index, first_word, item_count) in &self.dispatches {
            let item_words = self.item_words[index];
            let parameters = ScatterParameters {
                item_count,
                item_words,
                first_word,
            };
            record_dispatch(
                device,
                command_buffer,
                (scatter, pipelines.scatter_layout()),
                sets.sets[index],
                bytemuck::bytes_of(&parameters),
                (item_count * item_words).div_ceil(64),
            );
        }
        Ok(())
    }
}
