use std::path::PathBuf;

/// Everything that can go wrong below the renderer. User-facing variants name the device, the
/// feature or the file involved; Vulkan result codes are kept for the rest.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "cannot load the Vulkan loader (libvulkan.so.1): {0}; install it with `apt-get install libvulkan1 mesa-vulkan-drivers`"
    )]
    NoLoader(String),
    #[error(
        "no Vulkan device found: the loader reports no physical devices (is a driver installed? on Debian: `apt-get install mesa-vulkan-drivers` for lavapipe; VK_DRIVER_FILES={0})"
    )]
    NoDevices(String),
    #[error("no usable Vulkan device:\n{0}")]
    NoSuitableDevice(String),
    #[error(
        "validation was requested but the layer VK_LAYER_KHRONOS_validation is not installed (`apt-get install vulkan-validationlayers`)"
    )]
    NoValidationLayer,
    /// Something that would allocate memory or execute commands, asked of a device that can only
    /// compile pipelines (RADV's null winsys: `RADV_FORCE_FAMILY`, no memory heaps).
    #[error(
        "{what} needs a device that can execute, but `{device}` can only compile pipelines (RADV's null device, selected by RADV_FORCE_FAMILY: no memory, no queue submission); unset RADV_FORCE_FAMILY or choose another driver"
    )]
    CannotExecute { device: String, what: String },
    /// `RADV_FORCE_FAMILY` names a family this Mesa does not know (its driver would abort).
    #[error(
        "RADV_FORCE_FAMILY={family}: not a GPU family Mesa's RADV knows (it would abort); known: {known}"
    )]
    UnknownFamily { family: String, known: String },
    #[error("device `{device}` does not support {feature}")]
    Unsupported { device: String, feature: String },
    #[error("Vulkan call {call} failed: {result}")]
    Vk {
        call: &'static str,
        result: ash::vk::Result,
    },
    #[error("GPU memory allocation `{name}` failed: {source}")]
    Alloc {
        name: String,
        source: gpu_allocator::AllocationError,
    },
    #[error("shader {file}: {message}")]
    Shader { file: String, message: String },
    #[error("shader source `{0}` not found")]
    ShaderNotFound(PathBuf),
    /// A pass's declaration and what it was given disagree (a binding with nothing bound, one of
    /// the wrong kind, push constants of another size): a programming error, reported when the
    /// pass is built or recorded, never a panic.
    #[error("pass `{pass}`: {message}")]
    Declaration { pass: String, message: String },
    /// A configuration the technique or post pass refuses: the spec and the parameter.
    #[error("`{spec}`: {message}")]
    Config { spec: String, message: String },
    #[error("{0}")]
    Other(String),
}

pub type Result<T, E = GpuError> = std::result::Result<T, E>;

/// Attaches the name of the failing call to a raw `vk::Result`.
pub(crate) trait VkContext<T> {
    fn vk(self, call: &'static str) -> Result<T>;
}

impl<T> VkContext<T> for std::result::Result<T, ash::vk::Result> {
    fn vk(self, call: &'static str) -> Result<T> {
        self.map_err(|result| GpuError::Vk { call, result })
    }
}
