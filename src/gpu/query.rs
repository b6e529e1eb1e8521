//! Timestamp-query profiling scopes: `profiler.scope(rec, "name", |rec| record...)` brackets the
//! commands with two timestamps; after the submission has finished, [`Profiler::results`]
//! gives each scope's GPU time. Benchmarks use these to separate kernel time from the cost of
//! submitting and waiting.

use std::sync::Arc;

use ash::vk;

use super::context::{DeviceShared, Gpu};
use super::error::{GpuError, GpuResult, VkContext};
use super::lifetime::{Lifetime, Tracked};
use super::recorder::Recorder;

/// A pool of timestamp pairs, one pair per scope.
pub struct Profiler {
    life: Arc<Lifetime>,
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
        let life = Lifetime::new(&gpu.shared, "a timestamp query pool", move |dev| {
            // SAFETY: no recording writes the pool any more.
            unsafe { dev.raw.destroy_query_pool(pool, None) }
        });
        Ok(Self {
            life,
            shared: gpu.shared.clone(),
            pool,
            capacity: scopes.max(1),
            names: Vec::new(),
            period_ns,
        })
    }

    /// Records the reset of every query; call at the start of each recording that uses scopes.
    pub fn record_reset(&mut self, rec: &mut Recorder<'_>) {
        self.names.clear();
        rec.keep(&*self);
        // SAFETY: recording on this device (checked by `keep`), outside a render pass; the pool
        // is kept alive.
        unsafe { rec.device().cmd_reset_query_pool(rec.cmd(), self.pool, 0, 2 * self.capacity) };
    }

    /// Records `record` between two timestamps named `name`. Panics past the capacity.
    pub fn scope<'g, R>(
        &mut self,
        rec: &mut Recorder<'g>,
        name: &str,
        record: impl FnOnce(&mut Recorder<'g>) -> R,
    ) -> R {
        let i = self.names.len() as u32;
        assert!(i < self.capacity, "profiler holds {} scopes", self.capacity);
        self.names.push(name.to_string());
        rec.keep(&*self);
        // SAFETY: recording on this device; the queries were reset in this recording and the
        // pool is kept alive.
        unsafe {
            rec.device().cmd_write_timestamp(rec.cmd(), vk::PipelineStageFlags::TOP_OF_PIPE, self.pool, 2 * i)
        };
        let r = record(rec);
        // SAFETY: as above.
        unsafe {
            rec.device().cmd_write_timestamp(
                rec.cmd(),
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                self.pool,
                2 * i + 1,
            )
        };
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

impl Tracked for Profiler {
    fn lifetime(&self) -> &Arc<Lifetime> {
        &self.life
    }
}
