//! The error of a generated `Params::set` for a name the model does not have.

/// A parameter name that the model does not have. Allocation-free (`no_std`): the name
/// is kept inline, truncated to [`UnknownParameter::CAPACITY`] bytes.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct UnknownParameter {
    name: [u8; UnknownParameter::CAPACITY],
    len: u8,
}

impl UnknownParameter {
    /// The longest name kept, in bytes (longer names are cut at a character boundary).
    pub const CAPACITY: usize = 48;

    /// The error for `name` (truncated to [`UnknownParameter::CAPACITY`] bytes).
    pub fn new(name: &str) -> Self {
        let mut len = name.len().min(Self::CAPACITY);
        while !name.is_char_boundary(len) {
            len -= 1;
        }
        let mut buf = [0u8; Self::CAPACITY];
        buf[..len].copy_from_slice(&name.as_bytes()[..len]);
        Self {
            name: buf,
            len: len as u8,
        }
    }

    /// The name that was asked for (truncated to [`UnknownParameter::CAPACITY`] bytes).
    pub fn name(&self) -> &str {
        core::str::from_utf8(&self.name[..usize::from(self.len)]).unwrap_or("")
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
