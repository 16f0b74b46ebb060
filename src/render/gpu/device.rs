//! Adapters and devices: listing what Vulkan offers, choosing one, and opening it with its
//! real limits (never wgpu's conservative defaults, which would cap storage bindings) and
//! with hardware ray queries or without (`--accel`).

use super::error::GpuError;
use super::tables::scene_layout;
use std::sync::{Arc, Mutex};

/// How the GPU renderer finds the triangles a ray hits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Accel {
    /// Hardware ray queries where the adapter offers them, else the software BVH.
    Auto,
    /// The software BVH walk of `shaders/traverse.wgsl`, on any adapter.
    Software,
    /// Hardware ray queries (`shaders/ray_query.wgsl`); an error on an adapter without them.
    Hardware,
}

impl Accel {
    /// Whether a device on an adapter that does (`offered`) or does not offer ray queries
    /// traces with them; `Hardware` without them is [`GpuError::NoRayQuery`].
    pub fn resolve(self, adapter: &str, offered: bool) -> Result<bool, GpuError> {
        match self {
            Self::Auto => Ok(offered),
            Self::Software => Ok(false),
            Self::Hardware if offered => Ok(true),
            Self::Hardware => Err(GpuError::NoRayQuery(adapter.to_string())),
        }
    }
}

/// One adapter as `meshtrace adapters` lists it.
#[derive(Clone, Debug, PartialEq)]
pub struct AdapterSummary {
    pub index: usize,
    pub name: String,
    pub backend: String,
    pub device_type: String,
    pub driver: String,
    /// A driver that runs on the CPU, such as lavapipe: the GPU renderer works there, but
    /// the CPU renderer is faster on the same cores.
    pub software: bool,
    /// Whether the adapter offers hardware ray queries (wgpu's `EXPERIMENTAL_RAY_QUERY`).
    pub ray_query: bool,
}

fn instance() -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    // Vulkan is the backend meshtrace is built and tested for (and the only one compiled in).
    desc.backends = wgpu::Backends::VULKAN;
    wgpu::Instance::new(desc)
}

fn adapters(instance: &wgpu::Instance) -> Vec<wgpu::Adapter> {
    pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN))
}

fn summary(index: usize, a: &wgpu::Adapter) -> AdapterSummary {
    let info = a.get_info();
    let driver = [info.driver, info.driver_info]
        .into_iter()
        .filter(|s| !s.is_empty())
        .collect::<Vec<_>>()
        .join(" ");
    AdapterSummary {
        index,
        name: info.name,
        backend: format!("{:?}", info.backend),
        device_type: format!("{:?}", info.device_type),
        driver,
        software: info.device_type == wgpu::DeviceType::Cpu,
        ray_query: a
            .features()
            .contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY),
    }
}

/// Every adapter wgpu finds, in the order `--adapter INDEX` counts them.
pub fn list_adapters() -> Vec<AdapterSummary> {
    adapters(&instance())
        .iter()
        .enumerate()
        .map(|(i, a)| summary(i, a))
        .collect()
}

/// An open device with its queue, and what went wrong on it asynchronously. Cloning is
/// cheap and shares the device.
#[derive(Clone)]
pub struct GpuDevice {
    pub adapter: AdapterSummary,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub limits: wgpu::Limits,
    /// Whether this device traces with hardware ray queries (`shaders/ray_query.wgsl`)
    /// rather than the software BVH (`shaders/traverse.wgsl`).
    pub ray_query: bool,
    /// The layout of every scene's bind group on this device ([`scene_layout`]).
    pub scene_layout: wgpu::BindGroupLayout,
    fault: Arc<Mutex<Option<String>>>,
}

impl GpuDevice {
    /// Opens the adapter named by `spec` (an index or a case-insensitive name substring),
    /// else by `WGPU_ADAPTER_NAME`, else the first of the best kind: discrete, integrated,
    /// virtual, other, and software last. `accel` says whether it traces with hardware ray
    /// queries ([`Accel::resolve`]).
    pub fn new(spec: Option<&str>, accel: Accel) -> Result<Self, GpuError> {
        let all = adapters(&instance());
        let (index, _) = choose(&all, spec)?;
        let adapter = &all[index];
        let summary = summary(index, adapter);
        let ray_query = accel.resolve(&summary.name, summary.ray_query)?;
        // The adapter's own limits, acceleration-structure ones included (wgpu reports
        // them whether or not the feature is asked for).
        let limits = adapter.limits();
        let (required_features, experimental_features) = if ray_query {
            // SAFETY: wgpu asks for this token before it enables any EXPERIMENTAL_ feature,
            // as an acknowledgement that their implementation may still have bugs. meshtrace
            // uses only what `shaders/ray_query.wgsl` and `SceneAccel` need (one BLAS in one
            // TLAS, queries from a compute shader), which tests/ray_query.rs checks against
            // the software BVH.
            (wgpu::Features::EXPERIMENTAL_RAY_QUERY, unsafe {
                wgpu::ExperimentalFeatures::enabled()
            })
        } else {
            (
                wgpu::Features::empty(),
                wgpu::ExperimentalFeatures::disabled(),
            )
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("meshtrace"),
            required_features,
            required_limits: limits.clone(),
            experimental_features,
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| GpuError::Device(e.to_string()))?;
        let fault = Arc::new(Mutex::new(None));
        let f = fault.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            let mut slot = f.lock().unwrap_or_else(|p| p.into_inner());
            slot.get_or_insert_with(|| e.to_string().replace('\n', " "));
        }));
        let f = fault.clone();
        device.set_device_lost_callback(move |reason, message| {
            if reason != wgpu::DeviceLostReason::Destroyed {
                let mut slot = f.lock().unwrap_or_else(|p| p.into_inner());
                slot.get_or_insert_with(|| format!("device lost: {message}"));
            }
        });
        let scene_layout = scene_layout(&device, ray_query);
        Ok(Self {
            adapter: summary,
            device,
            queue,
            limits,
            ray_query,
            scene_layout,
            fault,
        })
    }

    /// How this device finds hits, for messages: "hardware ray queries" or "software BVH".
    pub fn accel_name(&self) -> &'static str {
        if self.ray_query {
            "hardware ray queries"
        } else {
            "software BVH"
        }
    }

    /// The first error the device reported since it was opened, if any.
    pub fn check(&self) -> Result<(), GpuError> {
        let slot = self.fault.lock().unwrap_or_else(|p| p.into_inner());
        match slot.as_ref() {
            Some(message) => Err(GpuError::Fault(message.clone())),
            None => Ok(()),
        }
    }

    /// Blocks until the queue's work is done.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Fault(e.to_string()))?;
        self.check()
    }

    /// Copies a buffer back to the host.
    pub fn read_buffer(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
        self.read_buffer_range(buffer, 0..buffer.size())
    }

    /// Bytes `range` of `buffer` (offsets and length multiples of 4), read back to the host.
    pub fn read_buffer_range(
        &self,
        buffer: &wgpu::Buffer,
        range: std::ops::Range<u64>,
    ) -> Result<Vec<u8>, GpuError> {
        let size = range.end - range.start;
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(buffer, range.start, &staging, 0, size);
        self.queue.submit([enc.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        staging.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.wait()?;
        rx.recv()
            .map_err(|e| GpuError::Fault(e.to_string()))?
            .map_err(|e| GpuError::Fault(e.to_string()))?;
        let data = staging
            .get_mapped_range(..)
            .map_err(|e| GpuError::Fault(e.to_string()))?
            .to_vec();
        staging.unmap();
        Ok(data)
    }
}

/// The adapter [`GpuDevice::new`] would open for `spec`, and whether it was asked for
/// (by `spec` or `WGPU_ADAPTER_NAME`) rather than ranked; no device is opened.
pub fn choose_adapter(spec: Option<&str>) -> Result<(AdapterSummary, bool), GpuError> {
    let all = adapters(&instance());
    let (index, named) = choose(&all, spec)?;
    Ok((summary(index, &all[index]), named))
}

/// The index of the adapter named by `spec`, else by `WGPU_ADAPTER_NAME`, else of the best
/// kind, and whether it was named.
fn choose(all: &[wgpu::Adapter], spec: Option<&str>) -> Result<(usize, bool), GpuError> {
    if all.is_empty() {
        return Err(GpuError::NoAdapter);
    }
    let env = std::env::var("WGPU_ADAPTER_NAME").ok();
    match spec.or(env.as_deref()) {
        Some(s) => Ok((pick(all, s)?, true)),
        None => Ok((
            (0..all.len())
                .min_by_key(|&i| preference(all[i].get_info().device_type))
                .unwrap_or(0),
            false,
        )),
    }
}

/// The rank of an adapter kind when none is asked for; lower is preferred.
fn preference(kind: wgpu::DeviceType) -> u8 {
    match kind {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

fn pick(all: &[wgpu::Adapter], spec: &str) -> Result<usize, GpuError> {
    if let Ok(i) = spec.parse::<usize>() {
        return if i < all.len() {
            Ok(i)
        } else {
            Err(GpuError::NoSuchAdapter(spec.to_string(), all.len()))
        };
    }
    let needle = spec.to_lowercase();
    all.iter()
        .position(|a| a.get_info().name.to_lowercase().contains(&needle))
        .ok_or_else(|| GpuError::NoSuchAdapter(spec.to_string(), all.len()))
}
