//! Timestamp-query profiling scopes: `profiler.scope(cmd, "name", || record...)` brackets the
//! commands with two timestamps; after the submission has finished, [`Profiler::results`]
//! gives each scope's GPU time. Benchmarks use these to separate kernel time from the cost of
//! submitting and waiting.

use std::sync::Arc;

use ash::vk;

use super::context::{DeviceShared, Gpu};
use super::error::{GpuError, GpuResult, VkContext};

/// A pool of timestamp pairs, one pair per scope.
pub struct Profiler {
    shared: Arc<DeviceShared>,
    pool: vk::QueryPool,
    capacity: u32,
    names: Vec<String>,
    period_ns: f64,
}

impl Profiler {
    /// A profiler for up to `scopes` scopes per recording. An error if the queue cannot write
    /// timestamps.
    pub fn new(gpu: &Gpu, scopes: u32) -> GpuResult<Self> {
        let period_ns = gpu
            .caps()
            .timestamp_period_ns
            .ok_or_else(|| GpuError::Unsupported("timestamp queries on the engine's queue".into()))?;
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(2 * scopes.max(1));
        // SAFETY: valid create info on this device.
        let pool = unsafe { gpu.device().create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
        Ok(Self { shared: gpu.shared.clone(), pool, capacity: scopes.max(1), names: Vec::new(), period_ns })
    }

    /// Records the reset of every query; call at the start of each recording that uses scopes.
    pub fn record_reset(&mut self, cmd: vk::CommandBuffer) {
        self.names.clear();
        // SAFETY: `cmd` is recording on this device, outside a render pass.
        unsafe { self.shared.raw.cmd_reset_query_pool(cmd, self.pool, 0, 2 * self.capacity) };
    }

    /// Records `record` between two timestamps named `name`. Panics past the capacity.
    pub fn scope<R>(&mut self, cmd: vk::CommandBuffer, name: &str, record: impl FnOnce() -> R) -> R {
        let i = self.names.len() as u32;
        assert!(i < self.capacity, "profiler holds {} scopes", self.capacity);
        self.names.push(name.to_string());
        let d = &self.shared.raw;
        // SAFETY: `cmd` is recording; the queries were reset in this recording.
        unsafe { d.cmd_write_timestamp(cmd, vk::PipelineStageFlags::TOP_OF_PIPE, self.pool, 2 * i) };
        let r = record();
        // SAFETY: as above.
        unsafe { d.cmd_write_timestamp(cmd, vk::PipelineStageFlags::BOTTOM_OF_PIPE, self.pool, 2 * i + 1) };
        r
    }

    /// Each scope's (name, milliseconds), once the recording's submission has finished.
    pub fn results(&self) -> GpuResult<Vec<(String, f64)>> {
        let n = self.names.len();
        if n == 0 {
            return Ok(Vec::new());
        }
        let mut ticks = vec![0u64; 2 * n];
        // SAFETY: the queries were written by a finished submission; WAIT is then immediate.
        unsafe {
            self.shared.raw.get_query_pool_results(
                self.pool,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .vk("vkGetQueryPoolResults")?;
        Ok(self
            .names
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let dt = ticks[2 * i + 1].wrapping_sub(ticks[2 * i]) as f64 * self.period_ns;
                (name.clone(), dt * 1e-6)
            })
            .collect())
    }
}

impl Drop for Profiler {
    fn drop(&mut self) {
        let pool = self.pool;
        self.shared.retire(move |dev| {
            // SAFETY: nothing in flight writes the pool.
            unsafe { dev.raw.destroy_query_pool(pool, None) }
        });
    }
}
