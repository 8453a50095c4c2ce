//! Per-pass GPU timestamps and pipeline statistics.
//!
//! lavapipe rule (PLATFORM.md): a compute dispatch between two timestamps reads ~0 ms unless a
//! barrier sits right after the start timestamp and right before the end one. Compute scopes get
//! those barriers (`compute_fences`, on by default); graphics intervals are right without them.
//!
//! Statistics: graphics and compute scopes count in separate pools with only their own counters.
//! lavapipe 22.3 crashes (SIGSEGV in its queue thread, no validation message) on any query that
//! counts COMPUTE_SHADER_INVOCATIONS, whatever it encloses, so there the compute pool is not made
//! (`Caps::compute_invocation_query`) and compute scopes have timestamps only.

use std::sync::Arc;

use ash::vk;

use crate::cmd::Cmd;
use crate::context::{Garbage, Gpu, Inner};
use crate::error::{Result, VkContext};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PassKind {
    Graphics,
    Compute,
    Transfer,
}

/// Device-independent cost counters of one pass.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct PipelineStats {
    pub vertex_invocations: u64,
    pub clipping_primitives: u64,
    pub fragment_invocations: u64,
    pub compute_invocations: u64,
}

/// What one pass moves and runs, counted while it is recorded (not measured): the bytes of the
/// images and buffers its declared reads and writes touch, each counted once in full (level 0,
/// every layer and sample; a pass that reads half an image still counts all of it), and the
/// compute invocations of its direct dispatches. The input of the static cost model
/// (`cbr gpu-stats`, docs/gpu-isa.md); the device never reports it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Traffic {
    pub bytes_read: u64,
    pub bytes_written: u64,
    /// Of `bytes_written`, those written to host-visible memory: cbr's readbacks for its own
    /// analysis, not part of a GPU frame.
    pub host_bytes_written: u64,
    /// Invocations of direct dispatches (groups x local size).
    pub compute_invocations: u64,
    pub dispatches: u32,
    /// Dispatches whose group counts the GPU writes (not in `compute_invocations`).
    pub indirect_dispatches: u32,
    /// Render passes begun (attachments counted in the bytes).
    pub render_passes: u32,
}

impl Traffic {
    pub fn add(&mut self, o: &Traffic) {
        self.bytes_read += o.bytes_read;
        self.bytes_written += o.bytes_written;
        self.host_bytes_written += o.host_bytes_written;
        self.compute_invocations += o.compute_invocations;
        self.dispatches += o.dispatches;
        self.indirect_dispatches += o.indirect_dispatches;
        self.render_passes += o.render_passes;
    }

    pub fn is_empty(&self) -> bool {
        *self == Traffic::default()
    }
}

/// One measured pass.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PassTiming {
    pub name: String,
    pub gpu_ms: f64,
    pub stats: Option<PipelineStats>,
    /// What the pass's recording declared it reads, writes and dispatches ([`Traffic`]).
    #[serde(skip_serializing_if = "Traffic::is_empty")]
    pub traffic: Traffic,
}

/// Counted in graphics scopes, in flag-bit order: vertex (bit 2), clipping primitives (6),
/// fragment (7).
const GRAPHICS_STATS: vk::QueryPipelineStatisticFlags = vk::QueryPipelineStatisticFlags::from_raw(
    vk::QueryPipelineStatisticFlags::VERTEX_SHADER_INVOCATIONS.as_raw()
        | vk::QueryPipelineStatisticFlags::CLIPPING_PRIMITIVES.as_raw()
        | vk::QueryPipelineStatisticFlags::FRAGMENT_SHADER_INVOCATIONS.as_raw(),
);
const COMPUTE_STATS: vk::QueryPipelineStatisticFlags =
    vk::QueryPipelineStatisticFlags::COMPUTE_SHADER_INVOCATIONS;

fn stats_pool(
    gpu: &Gpu,
    name: &str,
    capacity: u32,
    flags: vk::QueryPipelineStatisticFlags,
) -> Result<vk::QueryPool> {
    let info = vk::QueryPoolCreateInfo::default()
        .query_type(vk::QueryType::PIPELINE_STATISTICS)
        .query_count(capacity)
        .pipeline_statistics(flags);
    // SAFETY: valid create info; the feature is enabled (checked by the caller).
    let pool = unsafe { gpu.device().create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
    gpu.name_object(pool, name);
    Ok(pool)
}

pub struct Profiler {
    gpu: Arc<Inner>,
    timestamps: vk::QueryPool,
    /// (graphics, compute) statistics pools, indexed by scope.
    stats: Option<(vk::QueryPool, Option<vk::QueryPool>)>,
    capacity: u32,
    scopes: Vec<(String, PassKind)>,
    /// What each scope's recording declared (from [`Cmd::take_traffic`]).
    traffic: Vec<Traffic>,
    open: Option<u32>,
    period_ns: f64,
    /// Barriers around compute scopes (see module docs). Switchable to demonstrate the rule.
    pub compute_fences: bool,
}

/// Handle of an open scope.
#[must_use]
pub struct Scope(u32);

impl Profiler {
    pub fn new(gpu: &Gpu, name: &str, capacity: u32) -> Result<Profiler> {
        let dev = gpu.device();
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(capacity * 2);
        // SAFETY: valid create info.
        let timestamps = unsafe { dev.create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
        gpu.name_object(timestamps, &format!("{name}.timestamps"));
        let stats = if gpu.caps().pipeline_statistics {
            Some((
                stats_pool(
                    gpu,
                    &format!("{name}.graphics_statistics"),
                    capacity,
                    GRAPHICS_STATS,
                )?,
                if gpu.caps().compute_invocation_query {
                    Some(stats_pool(
                        gpu,
                        &format!("{name}.compute_statistics"),
                        capacity,
                        COMPUTE_STATS,
                    )?)
                } else {
                    None
                },
            ))
        } else {
            None
        };
        let p = Profiler {
            gpu: gpu.inner.clone(),
            timestamps,
            stats,
            capacity,
            scopes: Vec::new(),
            traffic: Vec::new(),
            open: None,
            period_ns: f64::from(gpu.caps().timestamp_period_ns),
            compute_fences: true,
        };
        p.reset();
        Ok(p)
    }

    /// Forgets the previous frame's scopes (host query reset).
    pub fn reset(&self) {
        // SAFETY: hostQueryReset is enabled; no submission using the pools is in flight (submissions
        // are waited on before results are read and before the next reset).
        unsafe {
            self.gpu
                .device
                .reset_query_pool(self.timestamps, 0, self.capacity * 2);
            if let Some((g, c)) = self.stats {
                self.gpu.device.reset_query_pool(g, 0, self.capacity);
                if let Some(c) = c {
                    self.gpu.device.reset_query_pool(c, 0, self.capacity);
                }
            }
        }
    }

    pub fn begin_frame(&mut self) {
        self.reset();
        self.scopes.clear();
        self.traffic.clear();
        self.open = None;
    }

    /// Opens a named scope. Scopes do not nest.
    pub fn begin(&mut self, cmd: &mut Cmd, name: &str, kind: PassKind) -> Scope {
        let i = self.scopes.len() as u32;
        assert!(
            i < self.capacity,
            "profiler capacity {} exceeded",
            self.capacity
        );
        assert!(self.open.is_none(), "profiler scopes do not nest");
        self.scopes.push((name.to_string(), kind));
        self.traffic.push(Traffic::default());
        self.open = Some(i);
        let dev = &self.gpu.device;
        // SAFETY: queries were reset; indices are in range.
        unsafe {
            dev.cmd_write_timestamp2(
                cmd.cb,
                vk::PipelineStageFlags2::ALL_COMMANDS,
                self.timestamps,
                2 * i,
            );
            if let Some(pool) = self.stats_pool(kind) {
                dev.cmd_begin_query(cmd.cb, pool, i, vk::QueryControlFlags::empty());
            }
        }
        if kind == PassKind::Compute && self.compute_fences {
            cmd.full_barrier();
        }
        Scope(i)
    }

    /// The N 64-bit counters of one statistics query, in flag-bit order.
    fn counters<const N: usize>(&self, pool: vk::QueryPool, query: u32) -> Result<[u64; N]> {
        let mut v = [[0u64; N]; 1];
        // SAFETY: the submission was waited on (and WAIT blocks until available); the pool was
        // created with exactly N counters per query.
        unsafe {
            self.gpu.device.get_query_pool_results(
                pool,
                query,
                &mut v,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .vk("vkGetQueryPoolResults")?;
        Ok(v[0])
    }

    fn stats_pool(&self, kind: PassKind) -> Option<vk::QueryPool> {
        match (self.stats, kind) {
            (Some((g, _)), PassKind::Graphics) => Some(g),
            (Some((_, Some(c))), PassKind::Compute) => Some(c),
            _ => None,
        }
    }

    pub fn end(&mut self, cmd: &mut Cmd, scope: Scope) {
        let i = scope.0;
        let kind = self.scopes[i as usize].1;
        // Everything declared since the previous scope ended: a pass's barriers and binds are
        // recorded just before its scope opens.
        self.traffic[i as usize] = cmd.take_traffic();
        if kind == PassKind::Compute && self.compute_fences {
            cmd.full_barrier();
        }
        let dev = &self.gpu.device;
        // SAFETY: paired with `begin`.
        unsafe {
            if let Some(pool) = self.stats_pool(kind) {
                dev.cmd_end_query(cmd.cb, pool, i);
            }
            dev.cmd_write_timestamp2(
                cmd.cb,
                vk::PipelineStageFlags2::ALL_COMMANDS,
                self.timestamps,
                2 * i + 1,
            );
        }
        self.open = None;
    }

    /// Results of the scopes recorded since `begin_frame`, once their submission has completed.
    pub fn results(&self) -> Result<Vec<PassTiming>> {
        let n = self.scopes.len();
        if n == 0 {
            return Ok(Vec::new());
        }
        let mut ts = vec![0u64; 2 * n];
        let dev = &self.gpu.device;
        // SAFETY: the submission was waited on; WAIT makes the call block until available.
        unsafe {
            dev.get_query_pool_results(
                self.timestamps,
                0,
                &mut ts,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .vk("vkGetQueryPoolResults")?;
        let mut out = Vec::with_capacity(n);
        for (i, (name, kind)) in self.scopes.iter().enumerate() {
            let stats = match self.stats_pool(*kind) {
                Some(pool) if *kind == PassKind::Graphics => {
                    let [vertex, clipping, fragment] = self.counters::<3>(pool, i as u32)?;
                    Some(PipelineStats {
                        vertex_invocations: vertex,
                        clipping_primitives: clipping,
                        fragment_invocations: fragment,
                        compute_invocations: 0,
                    })
                }
                Some(pool) => {
                    let [compute] = self.counters::<1>(pool, i as u32)?;
                    Some(PipelineStats {
                        compute_invocations: compute,
                        ..Default::default()
                    })
                }
                None => None,
            };
            out.push(PassTiming {
                name: name.clone(),
                gpu_ms: ts[2 * i + 1].saturating_sub(ts[2 * i]) as f64 * self.period_ns * 1e-6,
                stats,
                traffic: self.traffic[i],
            });
        }
        Ok(out)
    }
}

impl Drop for Profiler {
    fn drop(&mut self) {
        self.gpu.defer(Garbage::QueryPool(self.timestamps));
        if let Some((g, c)) = self.stats {
            self.gpu.defer(Garbage::QueryPool(g));
            if let Some(c) = c {
                self.gpu.defer(Garbage::QueryPool(c));
            }
        }
    }
}
