//! Errors of the host side (compiled without the `runtime` feature too: `McpgGpuParams::new`
//! returns them).

use core::fmt;

/// What went wrong while creating a [`GpuContext`](crate::GpuContext), a pipeline or a buffer,
/// or while reading results back.
///
/// Variants carry the values that explain them, as wgpu's errors do.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum GpuError {
    /// No wgpu adapter (GPU or software rasteriser) was found. `reason` is wgpu's message.
    /// On Linux without a GPU, install Mesa's lavapipe: `apt-get install mesa-vulkan-drivers
    /// libvulkan1`.
    NoAdapter {
        /// wgpu's description of why the request failed.
        reason: String,
    },
    /// The adapter was found but refused to create a device.
    RequestDevice {
        /// wgpu's description of the failure.
        reason: String,
    },
    /// A limit the kernels need is below what the adapter offers.
    LimitTooLow {
        /// Name of the limit (as in `wgpu::Limits`).
        limit: &'static str,
        /// What the kernels need.
        required: u64,
        /// What the adapter offers.
        available: u64,
    },
    /// A shader module or pipeline failed validation (naga or the driver).
    Shader {
        /// The entry point that was being built.
        entry_point: String,
        /// The validation message.
        message: String,
    },
    /// A dispatch asked for more workgroups than `max_compute_workgroups_per_dimension`.
    TooManyInvocations {
        /// Invocations asked for.
        requested: u64,
        /// The most one dispatch of this helper can run.
        maximum: u64,
    },
    /// Two inputs that go element by element (or an input and the buffer it is written into)
    /// differ in length.
    LengthMismatch {
        /// What the lengths must match: the first input's length or the buffer's.
        expected: usize,
        /// The length given.
        found: usize,
    },
    /// Mapping a buffer for read-back failed.
    Map {
        /// wgpu's description of the failure.
        reason: String,
    },
    /// A GPU guide's configuration is invalid (the CPU guide would reject it too).
    Guide(mcg_markov_guide::mcpg::GuideError),
    /// A GPU guide's buffer would exceed what one binding or one `u32` word index can address.
    GuideTooLarge {
        /// Bytes the buffer would need.
        bytes: u64,
        /// The most one binding may hold on this device.
        maximum: u64,
    },
}

impl fmt::Display for GpuError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GpuError::NoAdapter { reason } => write!(
                f,
                "no wgpu adapter found ({reason}); without a GPU install a software Vulkan \
                 driver, e.g. `apt-get install mesa-vulkan-drivers libvulkan1` (lavapipe)"
            ),
            GpuError::RequestDevice { reason } => {
                write!(f, "the adapter refused a device: {reason}")
            }
            GpuError::LimitTooLow {
                limit,
                required,
                available,
            } => write!(
                f,
                "adapter limit {limit} is {available}, the kernels need {required}"
            ),
            GpuError::Shader {
                entry_point,
                message,
            } => write!(f, "shader validation failed for `{entry_point}`: {message}"),
            GpuError::TooManyInvocations { requested, maximum } => write!(
                f,
                "dispatch of {requested} invocations exceeds the maximum of {maximum}"
            ),
            GpuError::LengthMismatch { expected, found } => write!(
                f,
                "length mismatch: expected {expected} elements, found {found}"
            ),
            GpuError::Map { reason } => {
                write!(f, "mapping a buffer for read-back failed: {reason}")
            }
            GpuError::Guide(e) => write!(f, "invalid guide configuration: {e}"),
            GpuError::GuideTooLarge { bytes, maximum } => write!(
                f,
                "a guide buffer of {bytes} bytes exceeds the binding maximum of {maximum}"
            ),
        }
    }
}

impl std::error::Error for GpuError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            GpuError::Guide(e) => Some(e),
            _ => None,
        }
    }
}

impl GpuError {
    /// `Ok` when `found == expected`, else [`GpuError::LengthMismatch`].
    #[cfg_attr(not(feature = "runtime"), allow(dead_code))] // used by the host types only
    pub(crate) fn check_len(expected: usize, found: usize) -> Result<(), GpuError> {
        if expected == found {
            Ok(())
        } else {
            Err(GpuError::LengthMismatch { expected, found })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_are_lowercase_and_explain() {
        let e = GpuError::LimitTooLow {
            limit: "max_storage_buffers_per_shader_stage",
            required: 4,
            available: 2,
        };
        let s = e.to_string();
        assert!(s.starts_with("adapter limit max_storage_buffers_per_shader_stage is 2"));
        let n = GpuError::NoAdapter {
            reason: "none".into(),
        };
        assert!(n.to_string().contains("mesa-vulkan-drivers"));
    }
}
