//! Recording several views' graphs in one frame, pass by pass: pass `p` of every view before
//! pass `p + 1` of any, so that the same pass of several views can be recorded together (the
//! instance cull testing every view in one dispatch, [`crate::graph::PassNode::record_together`]).
//! Each view's own passes keep their order, and views share nothing they write, so recording
//! them interleaved records the same work as one after the other.
//!
//! The one exception is a view that samples what other views draw (a camera view and its sun
//! shadow cascades): from its first pass that samples the shadow maps on, it waits until those
//! views have recorded all their passes and ended their frames, whose release of the maps is
//! the barrier its pass needs.

use super::view::{View, ViewId};
use crate::error::Result;
use crate::graph::executor::replay::{RecordedFrame, ReplayKey, Replays, SLOTS};
use crate::graph::{FrameData, FrameRecording, GraphRuntime, Imports};
use crate::passes::shared::SceneInputs;
use crate::render::RenderSettings;
use crate::scene::Camera;
use ash::vk;

/// One view's part of the frame.
pub(super) struct FramePart<'a> {
    view: &'a mut View,
    camera: &'a Camera,
    imports: &'a Imports,
    /// The parts (indices into the frame's list) that must have ended before this view's first
    /// pass sampling the shadow maps.
    pub waits_for: Vec<usize>,
    /// Where someone vouches for the images `imports` holds, what tells them apart from earlier
    /// ones that had their handles ([`FrameData::import_key`]): the shadow maps' array id for a
    /// map's layer, 0 for the renderer's own buffers (the scene's user data) or none, the host's
    /// generation where it vouches for its images ([`Imports::vouched`]); `None` for host
    /// images not vouched for, which may change between frames (the frame then never replays).
    pub import_key: Option<u64>,
    recording: Option<FrameRecording>,
    /// The next pass to record.
    next: usize,
    ended: bool,
}

impl<'a> FramePart<'a> {
    /// `view` seen by `camera` with `imports`, waiting for nothing.
    pub fn new(view: &'a mut View, camera: &'a Camera, imports: &'a Imports) -> Self {
        Self { view, camera, imports, waits_for: Vec::new(), import_key: None, recording: None, next: 0, ended: false }
    }

    fn passes(&self) -> usize {
        self.view.plan().passes.len()
    }

    /// The renderer's word on this part's frame ([`FrameData::replay_key`]: its inputs and the
    /// resources imported, and [`FrameData::import_key`]), where someone vouches for its
    /// imported images.
    fn keys(&self) -> (Option<u64>, Option<u64>) {
        use std::hash::{Hash, Hasher};
        let Some(images) = self.import_key else { return (None, None) };
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        (self.view.inputs.replay_key(), self.imports.fingerprint()).hash(&mut hasher);
        (Some(hasher.finish()), Some(images))
    }
}

/// What decides the commands of a frame of several parts: each part's view, runtime (a
/// reloaded or resized view has another), place in the order, waits and runtime key (with the
/// slot its runtime keeps frames in), and whether passes are recorded together.
#[derive(Clone, PartialEq)]
pub(super) struct FrameKey {
    together: bool,
    parts: Vec<(ViewId, u64, Vec<usize>, usize, ReplayKey)>,
}

/// A kept frame of several parts: its key, and what each part's runtime was left with.
pub(super) struct FrameRecorded {
    key: FrameKey,
    parts: Vec<RecordedFrame>,
}

/// The renderer's kept frames of several parts ([`crate::graph::executor::replay`]; a frame of
/// one view is kept by its runtime).
pub(super) type FrameReplays = Replays<FrameRecorded>;

/// Records renderer frame `frame` of `parts` (each with its camera and imports, in the order
/// given) into `cmd`. On an error every view's frame is abandoned: nothing is consumed.
///
/// A frame of several parts whose commands would be those kept for its slot replays them
/// (`replays`, made at the first such frame), as a runtime does for a frame of one view.
pub(super) fn record(
    ctx: &crate::gpu::GpuContext,
    cmd: vk::CommandBuffer,
    frame: u64,
    mut parts: Vec<FramePart<'_>>,
    together: bool,
    replays: &mut Option<FrameReplays>,
) -> Result<()> {
    for part in &mut parts {
        part.view.inputs.select(frame);
    }
    if let [one] = parts.as_mut_slice() {
        // One view: its graph whole, as a renderer of one view records it.
        return record_one(ctx, cmd, frame, one);
    }
    profiling::scope!("cullgraph::record_views");
    let slot = (frame % SLOTS as u64) as usize;
    let Some(key) = frame_key(frame, &parts, together) else {
        // The frame rewrites the slot's tables of views culled together, which the kept one
        // reads.
        if let Some(kept) = replays {
            kept.forget(slot);
        }
        return record_parts_whole(ctx, cmd, frame, &mut parts, together);
    };
    let kept = match replays.take() {
        Some(kept) => kept,
        None => Replays::new(ctx)?,
    };
    let kept = replays.insert(kept);
    if let Some(recorded) = kept.get(slot).filter(|r| r.key == key) {
        kept.execute(cmd, slot);
        for (part, left) in parts.iter_mut().zip(&recorded.parts) {
            let local = part.view.graphs.runtime.replayed_frame(left);
            part.view.graphs.recorded(frame, local);
            part.view.previous_camera = Some(part.camera.clone());
        }
        return Ok(());
    }
    let secondary = kept.begin(slot)?;
    let recorded = record_parts_whole(ctx, secondary, frame, &mut parts, together);
    let left = recorded
        .is_ok()
        .then(|| FrameRecorded { key, parts: parts.iter().map(|p| p.view.graphs.runtime.recorded_frame()).collect() });
    let ended = kept.end(slot, left);
    recorded?;
    ended?;
    kept.execute(cmd, slot);
    Ok(())
}

/// The key of a frame of `parts`, when every part may replay.
fn frame_key(frame: u64, parts: &[FramePart<'_>], together: bool) -> Option<FrameKey> {
    let mut keys = Vec::with_capacity(parts.len());
    for part in parts {
        let (replay_key, import_key) = part.keys();
        let View { graphs, inputs, settings, id, .. } = &*part.view;
        let data = frame_data(frame, settings, inputs, (replay_key, import_key));
        let key = graphs.runtime.replay_key(&data, part.imports)?;
        let runtime = &graphs.runtime;
        keys.push((*id, runtime.id(), part.waits_for.clone(), runtime.replay_slot(), key));
    }
    Some(FrameKey { together, parts: keys })
}

/// What a view's graph takes for frame `frame`: its size, its inputs and the renderer's `keys`
/// ([`FramePart::keys`]).
fn frame_data<'a>(
    frame: u64,
    settings: &RenderSettings,
    inputs: &'a SceneInputs,
    (replay_key, import_key): (Option<u64>, Option<u64>),
) -> FrameData<'a> {
    FrameData {
        frame,
        extent: vk::Extent2D { width: settings.width, height: settings.height },
        shared: inputs,
        replay_key,
        import_key,
    }
}

/// [`record_parts`], every view's frame abandoned on an error.
fn record_parts_whole(
    ctx: &crate::gpu::GpuContext,
    cmd: vk::CommandBuffer,
    frame: u64,
    parts: &mut [FramePart<'_>],
    together: bool,
) -> Result<()> {
    let recorded = record_parts(ctx, cmd, frame, parts, together);
    if recorded.is_err() {
        for part in parts.iter_mut() {
            if let Some(recording) = part.recording.take() {
                part.view.graphs.runtime.abandon_frame(recording);
            }
        }
    }
    recorded
}

fn record_one(
    ctx: &crate::gpu::GpuContext,
    cmd: vk::CommandBuffer,
    frame: u64,
    part: &mut FramePart<'_>,
) -> Result<()> {
    let (replay_key, import_key) = part.keys();
    let View { graphs, inputs, settings, id, .. } = &mut *part.view;
    let data = frame_data(frame, settings, inputs, (replay_key, import_key));
    ctx.begin_label(cmd, &id.to_string());
    let recorded = graphs.runtime.record(cmd, &data, part.imports);
    ctx.end_label(cmd);
    let local = recorded.map_err(|e| id.error(e))?;
    graphs.recorded(frame, local);
    part.view.previous_camera = Some(part.camera.clone());
    Ok(())
}

/// Whether part `i` may record its next pass now: it has one, and it does not wait for parts
/// that have not ended.
fn ready(parts: &[FramePart<'_>], i: usize) -> bool {
    let part = &parts[i];
    if part.next >= part.passes() {
        return false;
    }
    let waiting = !part.waits_for.is_empty()
        && part.view.graphs.runtime.first_pass_sampling_shadows().is_some_and(|first| part.next >= first);
    !waiting || part.waits_for.iter().all(|&p| parts[p].ended)
}

fn end_part(cmd: vk::CommandBuffer, frame: u64, part: &mut FramePart<'_>) {
    let recording = part.recording.take().expect("begun");
    let local = part.view.graphs.runtime.end_frame(recording, cmd, part.imports);
    part.view.graphs.recorded(frame, local);
    part.view.previous_camera = Some(part.camera.clone());
    part.ended = true;
}

fn record_parts(
    ctx: &crate::gpu::GpuContext,
    cmd: vk::CommandBuffer,
    frame: u64,
    parts: &mut [FramePart<'_>],
    together: bool,
) -> Result<()> {
    for part in parts.iter_mut() {
        let import_key = part.keys().1;
        let runtime = &mut part.view.graphs.runtime;
        let recording = runtime.begin_frame_keyed(cmd, part.imports, import_key).map_err(|e| part.view.error(e))?;
        part.recording = Some(recording);
    }
    let awaited: Vec<usize> = parts.iter().flat_map(|p| p.waits_for.iter().copied()).collect();
    loop {
        let ready_parts: Vec<usize> = (0..parts.len()).filter(|&i| ready(parts, i)).collect();
        let Some(index) = ready_parts.iter().map(|&i| parts[i].next).min() else { break };
        // The ready views at pass `index`, grouped by what can be recorded together.
        let mut left: Vec<usize> = ready_parts.into_iter().filter(|&i| parts[i].next == index).collect();
        while let Some(&first) = left.first() {
            let key = parts[first].view.graphs.runtime.together_key(index).filter(|_| together);
            let group: Vec<usize> = match &key {
                Some(key) => left
                    .iter()
                    .copied()
                    .filter(|&i| parts[i].view.graphs.runtime.together_key(index).as_ref() == Some(key))
                    .collect(),
                None => vec![first],
            };
            left.retain(|i| !group.contains(i));
            record_group(ctx, cmd, frame, parts, &group, index)?;
            for &i in &group {
                parts[i].next += 1;
                // A view others wait for ends its frame at once: that releases what they sample.
                if parts[i].next == parts[i].passes() && awaited.contains(&i) {
                    end_part(cmd, frame, &mut parts[i]);
                }
            }
        }
    }
    for part in parts.iter_mut().filter(|p| !p.ended) {
        end_part(cmd, frame, part);
    }
    Ok(())
}

/// Records pass `index` of the views `group` (indices into `parts`): together when there are
/// several.
fn record_group(
    ctx: &crate::gpu::GpuContext,
    cmd: vk::CommandBuffer,
    frame: u64,
    parts: &mut [FramePart<'_>],
    group: &[usize],
    index: usize,
) -> Result<()> {
    let mut chosen: Vec<&mut FramePart<'_>> =
        parts.iter_mut().enumerate().filter(|(i, _)| group.contains(i)).map(|(_, p)| p).collect();
    let first_id = chosen[0].view.id;
    let mut runtimes: Vec<&mut GraphRuntime> = Vec::with_capacity(chosen.len());
    let mut inputs: Vec<FrameData<'_>> = Vec::with_capacity(chosen.len());
    let mut recordings: Vec<&FrameRecording> = Vec::with_capacity(chosen.len());
    for part in chosen.iter_mut() {
        let View { graphs, inputs: shared, settings, .. } = &mut *part.view;
        inputs.push(frame_data(frame, settings, shared, (None, None)));
        runtimes.push(&mut graphs.runtime);
        recordings.push(part.recording.as_ref().expect("begun"));
    }
    if runtimes.len() == 1 {
        ctx.begin_label(cmd, &first_id.to_string());
        let recorded = runtimes[0].record_pass(recordings[0], cmd, index, &inputs[0]);
        ctx.end_label(cmd);
        return recorded.map_err(|e| first_id.error(e));
    }
    GraphRuntime::record_passes_together(&mut runtimes, &recordings, cmd, index, &inputs).map_err(|e| first_id.error(e))
}
