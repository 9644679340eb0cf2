//! GPU timing with timestamp queries: a begin/end pair per pass, read back as plain data.

use super::context::{DeviceShared, GpuContext};
use super::error::{GpuResult, VkResultExt};
use ash::vk;
use std::sync::Arc;

/// The measured GPU time of one named scope: its timestamp pair, as an offset and a length.
///
/// `start_ms` places the scope on the frame's GPU timeline (0 is the frame's first timestamp),
/// so that a host can draw the passes as GPU zones in its own profiler.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PassTiming {
    /// Scope (pass) name.
    pub name: String,
    /// Milliseconds from the frame's first timestamp (the first scope's begin) to this scope's
    /// begin.
    #[serde(default)]
    pub start_ms: f64,
    /// Milliseconds between the scope's begin and end timestamps.
    pub ms: f64,
}

/// A pool of timestamp pairs for one frame's worth of scopes.
///
/// Usage per frame: [`GpuTimer::reset`] at the start of the command buffer, then
/// [`GpuTimer::begin`]/[`GpuTimer::end`] around each pass, and after the command buffer has
/// completed, [`GpuTimer::results`].
pub struct GpuTimer {
    shared: Arc<DeviceShared>,
    pool: vk::QueryPool,
    capacity: u32,
    names: Vec<String>,
    open: Vec<u32>,
    period_ns: f64,
    valid_mask: u64,
    enabled: bool,
}

impl GpuTimer {
    /// A timer for up to `max_scopes` scopes per frame. Without timestamp support it records nothing.
    pub fn new(ctx: &GpuContext, max_scopes: u32) -> GpuResult<Self> {
        let caps = ctx.caps();
        let enabled = caps.timestamp_valid_bits > 0 && caps.limits.timestamp_compute_and_graphics == vk::TRUE;
        let capacity = max_scopes.max(1) * 2;
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(capacity);
        // SAFETY: valid device.
        let pool = unsafe { ctx.device().create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
        let bits = caps.timestamp_valid_bits;
        Ok(Self {
            shared: ctx.shared.clone(),
            pool,
            capacity,
            names: Vec::new(),
            open: Vec::new(),
            period_ns: caps.timestamp_period_ns,
            valid_mask: if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 },
            enabled,
        })
    }

    /// Starts a frame: forgets the previous scopes and resets the queries in `cmd`.
    pub fn reset(&mut self, cmd: vk::CommandBuffer) {
        self.names.clear();
        self.open.clear();
        if self.enabled {
            // SAFETY: cmd recording, pool valid, range within capacity.
            unsafe { self.shared.device.cmd_reset_query_pool(cmd, self.pool, 0, self.capacity) };
        }
    }

    /// Opens scope `name`; scopes beyond the capacity are silently not timed (and not reported).
    pub fn begin(&mut self, cmd: vk::CommandBuffer, name: &str) {
        let index = self.names.len() as u32;
        self.open.push(index);
        self.names.push(name.to_string());
        if self.enabled && index * 2 + 1 < self.capacity {
            // SAFETY: query index within the pool, reset this frame.
            unsafe {
                self.shared.device.cmd_write_timestamp2(
                    cmd,
                    vk::PipelineStageFlags2::ALL_COMMANDS,
                    self.pool,
                    index * 2,
                )
            };
        }
    }

    /// Closes the innermost open scope.
    pub fn end(&mut self, cmd: vk::CommandBuffer) {
        let Some(index) = self.open.pop() else { return };
        if self.enabled && index * 2 + 1 < self.capacity {
            // SAFETY: as in begin.
            unsafe {
                self.shared.device.cmd_write_timestamp2(
                    cmd,
                    vk::PipelineStageFlags2::ALL_COMMANDS,
                    self.pool,
                    index * 2 + 1,
                )
            };
        }
    }

    /// The names of the scopes recorded since the last [`GpuTimer::reset`], in the order they
    /// began.
    pub fn scopes(&self) -> &[String] {
        &self.names
    }

    /// Takes `names` as the scopes of the frame about to execute: for commands recorded
    /// earlier (and replayed) that reset the queries and wrote those scopes.
    pub fn replayed(&mut self, names: &[String]) {
        self.names.clear();
        self.names.extend_from_slice(names);
        self.open.clear();
    }

    /// The scopes of the last frame, in the order they began. Call after the frame's work completed.
    pub fn results(&self) -> GpuResult<Vec<PassTiming>> {
        let count = (self.names.len() as u32 * 2).min(self.capacity);
        if !self.enabled || count == 0 {
            return Ok(Vec::new());
        }
        let mut raw = vec![[0u64; 2]; count as usize];
        // SAFETY: queries were written by a completed command buffer; WITH_AVAILABILITY pairs each value.
        unsafe {
            self.shared.device.get_query_pool_results(
                self.pool,
                0,
                &mut raw,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WITH_AVAILABILITY,
            )
        }
        .vk("vkGetQueryPoolResults")?;
        // Ticks from `from` to `to`, across a wrap of the valid bits.
        let span = |from: u64, to: u64| (to & self.valid_mask).wrapping_sub(from & self.valid_mask) & self.valid_mask;
        let ms = |ticks: u64| ticks as f64 * self.period_ns * 1e-6;
        let origin = raw[0][0];
        Ok(self
            .names
            .iter()
            .enumerate()
            .filter(|(i, _)| (*i as u32) * 2 + 1 < count)
            .filter_map(|(i, name)| {
                let (b, e) = (raw[i * 2], raw[i * 2 + 1]);
                (b[1] != 0 && e[1] != 0).then(|| PassTiming {
                    name: name.clone(),
                    start_ms: ms(span(origin, b[0])),
                    ms: ms(span(b[0], e[0])),
                })
            })
            .collect())
    }
}

impl Drop for GpuTimer {
    fn drop(&mut self) {
        // SAFETY: the caller guarantees no command buffer using the pool is pending.
        unsafe { self.shared.device.destroy_query_pool(self.pool, None) };
    }
}
