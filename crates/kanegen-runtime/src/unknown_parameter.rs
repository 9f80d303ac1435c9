//! The error of a generated `Params::set` for a name the model does not have.

/// A name kept inline (no allocation), truncated to [`UnknownParameter::CAPACITY`] bytes at a
/// character boundary.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) struct InlineName {
    bytes: [u8; UnknownParameter::CAPACITY],
    len: u8,
}

impl InlineName {
    pub(crate) fn new(name: &str) -> Self {
        let mut len = name.len().min(UnknownParameter::CAPACITY);
        while !name.is_char_boundary(len) {
            len -= 1;
        }
        let mut bytes = [0u8; UnknownParameter::CAPACITY];
        bytes[..len].copy_from_slice(&name.as_bytes()[..len]);
        Self {
            bytes,
            len: len as u8,
        }
    }

    pub(crate) fn as_str(&self) -> &str {
        core::str::from_utf8(&self.bytes[..usize::from(self.len)]).unwrap_or("")
    }
}

/// A parameter name that the model does not have. Allocation-free (`no_std`): the name
/// is kept inline, truncated to [`UnknownParameter::CAPACITY`] bytes.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct UnknownParameter {
    name: InlineName,
}

impl UnknownParameter {
    /// The longest name kept, in bytes (longer names are cut at a character boundary); also
    /// for [`InvalidParameter`](crate::InvalidParameter).
    pub const CAPACITY: usize = 48;

    /// The error for `name` (truncated to [`UnknownParameter::CAPACITY`] bytes).
    pub fn new(name: &str) -> Self {
        Self {
            name: InlineName::new(name),
        }
    }

    /// The name that was asked for (truncated to [`UnknownParameter::CAPACITY`] bytes).
    pub fn name(&self) -> &str {
        self.name.as_str()
    }
}

impl core::fmt::Debug for UnknownParameter {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("UnknownParameter")
            .field("name", &self.name())
            .finish()
    }
}

impl core::fmt::Display for UnknownParameter {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "unknown parameter `{}`; the valid names are listed in Params::NAMES",
            self.name()
        )
    }
}

impl core::error::Error for UnknownParameter {}
