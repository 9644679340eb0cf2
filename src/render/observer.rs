//! Observers of frames: what looks at each headless frame once it has completed and adds its
//! findings to the frame's stats. Verification (exact visibility, `cullgraph::oracle`) attaches
//! this way, from outside the renderer, like an engine's own checks.

use super::{Renderer, ViewId};
use crate::error::Result;
use crate::stats::FrameStats;
use std::any::Any;

/// Looks at every frame of every view that [`Renderer::render`] (and its variants, such as
/// [`Renderer::render_views`]) waits for.
pub trait FrameObserver: Any + Send {
    /// Whether the renderer must capture what each pass drew ([`Renderer::drawn_in_view`]): it copies
    /// the draw lists to the host after each pass, which costs a little every frame.
    fn needs_draw_lists(&self) -> bool {
        false
    }

    /// Frame `frame` of `view` of `renderer` has completed on the GPU (its per-frame data,
    /// captures and counters are readable): look at it and add to `stats` (that view's).
    fn completed(&mut self, renderer: &Renderer, view: ViewId, frame: u64, stats: &mut FrameStats) -> Result<()>;
}
