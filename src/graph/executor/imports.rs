//! Resources a host engine hands to a frame (`Imported(...)` in RON): its images and buffers,
//! the access they are in now, and the access to leave them in.

use crate::gpu::{Access, HostImage};
use ash::vk;
use std::collections::BTreeMap;

/// One host resource.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
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
    /// The host's word on its images ([`Imports::vouched`]).
    generation: Option<u64>,
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

    /// The host's word that every image it gives in frames vouched for with `generation` is
    /// one it has not destroyed since it first gave it under that generation (even where
    /// Vulkan would give a new image the old one's handles). cullgraph then keeps the views it
    /// makes of the images from frame to frame (up to six per imported resource, the images of
    /// a swapchain), and a frame whose commands would not change replays an earlier frame's
    /// recording (`Renderer::set_frame_replay`). Give a new generation whenever images may
    /// have been destroyed and made anew (a swapchain recreated); without this word the views
    /// are made every frame and a frame importing an image records every pass.
    pub fn vouched(mut self, generation: u64) -> Self {
        self.generation = Some(generation);
        self
    }

    /// The generation the host vouches for its images under ([`Imports::vouched`]).
    pub fn generation(&self) -> Option<u64> {
        self.generation
    }

    /// A hash of every resource given (handles, sizes, accesses): equal for imports that would
    /// bind the same resources the same way.
    pub(crate) fn fingerprint(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        self.entries.hash(&mut hasher);
        hasher.finish()
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
