//! The one error type of the crate. Every fallible public call returns `Result<_, Error>`;
//! nothing in Nimbus panics on bad input.

/// What went wrong, with a message meant for a human reading a log.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A field of [`crate::Settings`] is out of range or not finite.
    #[error("invalid setting `{field}`: {reason}")]
    InvalidSettings {
        /// Path of the offending field, e.g. `weather.layer.bottom_altitude`.
        field: String,
        /// Why it was refused.
        reason: String,
    },
    /// A per-frame input (camera, sun, time) is unusable.
    #[error("invalid frame input `{field}`: {reason}")]
    InvalidFrame {
        /// Name of the offending input, e.g. `camera.view`.
        field: &'static str,
        /// Why it was refused.
        reason: String,
    },
    /// A render target has the wrong size, usage or dimension.
    #[error("invalid target `{target}`: {reason}")]
    InvalidTarget {
        /// Which target: `scene_color`, `scene_depth` or `output`.
        target: &'static str,
        /// Why it was refused.
        reason: String,
    },
    /// A render target's texture format cannot be used for that role.
    #[error("unsupported format {format:?} for `{target}`; supported: {supported}")]
    UnsupportedFormat {
        /// Which target.
        target: &'static str,
        /// The format that was given.
        format: wgpu::TextureFormat,
        /// The formats that would be accepted.
        supported: &'static str,
    },
    /// A weather preset file could not be read, parsed or validated.
    #[error("preset {origin}{}{}: {message}", line.map(|l| format!(", line {l}")).unwrap_or_default(), field.as_ref().map(|f| format!(", field `{f}`")).unwrap_or_default())]
    PresetFile {
        /// The file path, or `<string>` for text.
        origin: String,
        /// 1-based line of the problem, when known.
        line: Option<usize>,
        /// Dotted path of the offending field, when known.
        field: Option<String>,
        /// What is wrong.
        message: String,
    },
    /// A weather request is unusable (bad duration, out of time order).
    #[error("invalid weather request: {0}")]
    InvalidWeather(String),
    /// A view id that names no live view, or too many views.
    #[error("view: {0}")]
    InvalidView(String),
    /// A CPU query's point, segment or time is unusable (NaN, infinite).
    #[error("invalid query: {0}")]
    InvalidQuery(String),
    /// `encode` was called before any successful `prepare`, or after `set_settings` without
    /// a `prepare` since (the prepared frame was made from the old settings).
    #[error("renderer not prepared: call prepare() with the frame inputs before encode(), and again after set_settings()")]
    NotPrepared,
    /// No GPU adapter (software Vulkan included) could be found.
    #[error("no GPU adapter found: {0}")]
    NoAdapter(String),
    /// The adapter refused to create a device.
    #[error("could not create a GPU device: {0}")]
    RequestDevice(String),
    /// A window surface could not be created, configured or acquired.
    #[error("window surface: {0}")]
    Surface(String),
    /// wgpu reported a validation or out-of-memory error.
    #[error("GPU error: {0}")]
    Gpu(String),
    /// The GPU device was lost (driver reset, device removed, `Device::destroy`). Everything
    /// made on it is unusable: make a new device (or `Headless`).
    #[error("the GPU device was lost ({0}); everything made on it is unusable")]
    DeviceLost(String),
    /// The host's Vulkan instance, device or queue lacks what Nimbus needs (an API version,
    /// an extension, a feature, a usable queue family), or describes it inconsistently. The
    /// message names what is missing.
    #[error("host Vulkan device: {0}")]
    Vulkan(String),
    /// Reading a texture back to the CPU failed.
    #[error("GPU readback failed: {0}")]
    Readback(String),
    /// Writing or encoding an image failed.
    #[error("image output failed: {0}")]
    Image(String),
    /// A noise cache (see [`crate::noise_cache`]) is malformed, damaged, from another noise
    /// algorithm, or holds other volumes than the settings ask for.
    #[error("noise cache: {0}")]
    NoiseCache(String),
}

/// Shorthand used throughout the crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

pub(crate) fn invalid_frame(field: &'static str, reason: impl Into<String>) -> Error {
    Error::InvalidFrame {
        field,
        reason: reason.into(),
    }
}

pub(crate) fn invalid_target(target: &'static str, reason: impl Into<String>) -> Error {
    Error::InvalidTarget {
        target,
        reason: reason.into(),
    }
}
