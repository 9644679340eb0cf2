//! Recording several views' graphs in one frame, pass by pass: pass `p` of every view before
//! pass `p + 1` of any, so that the same pass of several views can be recorded together (the
//! instance cull testing every view in one dispatch, [`crate::graph::PassNode::record_together`]).
//! Each view's own passes keep their order, and views share nothing they write, so recording
//! them interleaved records the same work as one after the other.

use super::view::View;
use crate::error::Result;
use crate::graph::{FrameData, FrameRecording, GraphRuntime, Imports};
use crate::scene::Camera;
use ash::vk;

/// One view's part of the frame.
struct Part<'a> {
    view: &'a mut View,
    camera: &'a Camera,
    imports: &'a Imports,
    recording: Option<FrameRecording>,
}

/// Records renderer frame `frame` of `views` (each with its camera and imports, in the order
/// given) into `cmd`. On an error every view's frame is abandoned: nothing is consumed.
pub(super) fn record(
    ctx: &crate::gpu::GpuContext,
    cmd: vk::CommandBuffer,
    frame: u64,
    views: Vec<(&mut View, &Camera, &Imports)>,
    together: bool,
) -> Result<()> {
    let mut parts: Vec<Part<'_>> =
        views.into_iter().map(|(view, camera, imports)| Part { view, camera, imports, recording: None }).collect();
    for part in &mut parts {
        part.view.inputs.select(frame);
    }
    if let [one] = parts.as_mut_slice() {
        // One view: its graph whole, as a renderer of one view records it.
        return record_one(ctx, cmd, frame, one);
    }
    profiling::scope!("cullgraph::record_views");
    let recorded = record_parts(ctx, cmd, frame, &mut parts, together);
    if recorded.is_err() {
        for part in &mut parts {
            if let Some(recording) = part.recording.take() {
                part.view.graphs.runtime.abandon_frame(recording);
            }
        }
    }
    recorded
}

fn record_one(ctx: &crate::gpu::GpuContext, cmd: vk::CommandBuffer, frame: u64, part: &mut Part<'_>) -> Result<()> {
    let View { graphs, inputs, settings, id, .. } = &mut *part.view;
    let data =
        FrameData { frame, extent: vk::Extent2D { width: settings.width, height: settings.height }, shared: &*inputs };
    ctx.begin_label(cmd, &id.to_string());
    let recorded = graphs.runtime.record(cmd, &data, part.imports);
    ctx.end_label(cmd);
    let local = recorded.map_err(|e| id.error(e))?;
    graphs.recorded(frame, local);
    part.view.previous_camera = Some(part.camera.clone());
    Ok(())
}

fn record_parts(
    ctx: &crate::gpu::GpuContext,
    cmd: vk::CommandBuffer,
    frame: u64,
    parts: &mut [Part<'_>],
    together: bool,
) -> Result<()> {
    for part in parts.iter_mut() {
        let recording = part.view.graphs.runtime.begin_frame(cmd, part.imports).map_err(|e| part.view.error(e))?;
        part.recording = Some(recording);
    }
    let most = parts.iter().map(|p| p.view.plan().passes.len()).max().unwrap_or(0);
    for index in 0..most {
        // The views with a pass at `index`, grouped by what can be recorded together.
        let mut left: Vec<usize> = (0..parts.len()).filter(|&i| index < parts[i].view.plan().passes.len()).collect();
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
        }
    }
    for part in parts.iter_mut() {
        let recording = part.recording.take().expect("begun above");
        let local = part.view.graphs.runtime.end_frame(recording, cmd, part.imports);
        part.view.graphs.recorded(frame, local);
        part.view.previous_camera = Some(part.camera.clone());
    }
    Ok(())
}

/// Records pass `index` of the views `group` (indices into `parts`): together when there are
/// several.
fn record_group(
    ctx: &crate::gpu::GpuContext,
    cmd: vk::CommandBuffer,
    frame: u64,
    parts: &mut [Part<'_>],
    group: &[usize],
    index: usize,
) -> Result<()> {
    let mut chosen: Vec<&mut Part<'_>> =
        parts.iter_mut().enumerate().filter(|(i, _)| group.contains(i)).map(|(_, p)| p).collect();
    let first_id = chosen[0].view.id;
    let mut runtimes: Vec<&mut GraphRuntime> = Vec::with_capacity(chosen.len());
    let mut inputs: Vec<FrameData<'_>> = Vec::with_capacity(chosen.len());
    let mut recordings: Vec<&FrameRecording> = Vec::with_capacity(chosen.len());
    for part in chosen.iter_mut() {
        let View { graphs, inputs: shared, settings, .. } = &mut *part.view;
        inputs.push(FrameData {
            frame,
            extent: vk::Extent2D { width: settings.width, height: settings.height },
            shared: &*shared,
        });
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
