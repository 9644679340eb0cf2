//! Resources a host engine hands to a frame (`Imported(...)` in RON): its images and buffers,
//! the access they are in now, and the access to leave them in.

use crate::gpu::{Access, HostImage};
use ash::vk;
use std::collections::BTreeMap;

/// One host resource.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Import {
    /// A host image.
    Image {
        /// The image and its view.
        host: HostImage,
        /// How the host last used it (stage, access, current layout).
        current: Access,
        /// How the host will use it after the frame (the graph leaves it in this layout).
        after: Access,
    },
    /// A host buffer.
    Buffer {
        /// The buffer.
        buffer: vk::Buffer,
        /// Its size in bytes.
        size: u64,
        /// How the host last used it.
        current: Access,
        /// How the host will use it after the frame.
        after: Access,
    },
}

/// The host resources of one frame, by the names the graph declares them under.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Imports {
    entries: BTreeMap<String, Import>,
}

impl Imports {
    /// No imports.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the host image for the graph's `Imported(Image(..))` resource `name`.
    pub fn image(mut self, name: &str, host: HostImage, current: Access, after: Access) -> Self {
        self.entries.insert(name.into(), Import::Image { host, current, after });
        self
    }

    /// Adds the host buffer for the graph's `Imported(Buffer(..))` resource `name`.
    pub fn buffer(mut self, name: &str, buffer: vk::Buffer, size: u64, current: Access, after: Access) -> Self {
        self.entries.insert(name.into(), Import::Buffer { buffer, size, current, after });
        self
    }

    /// Whether any import is an image (whose views are made anew every frame).
    pub(crate) fn has_images(&self) -> bool {
        self.entries.values().any(|i| matches!(i, Import::Image { .. }))
    }

    /// The import named `name`.
    pub fn get(&self, name: &str) -> Option<&Import> {
        self.entries.get(name)
    }

    /// The names given.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.entries.keys().map(String::as_str)
    }
}
