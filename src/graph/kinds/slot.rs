//! What a pass kind declares of each slot: how it uses what is bound there, which formats and
//! sizes it takes, the resource it creates itself when the graph declares none, and whether the
//! slot holds counters the host reads back.

use crate::graph::usage::Usage;
use ash::vk;

/// Which formats a slot accepts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FormatRule {
    /// Any format the usage supports on the device.
    Any,
    /// Any depth format.
    Depth,
    /// Any depth format with a stencil aspect.
    DepthStencil,
    /// Any color (non-depth) format.
    Color,
    /// Exactly this format (the pass's shaders are written for it).
    Exact(vk::Format),
    /// One of these formats (the pass compiles its shaders for the one bound).
    OneOf(&'static [vk::Format]),
}

/// How many bytes a buffer bound to a slot must hold, as an expression over the output size
/// (`width`, `height`), the host's quantities (`instances`, `meshes`, ...) and the pass's own
/// numeric settings (by name). The expression is checked when the kind is registered and
/// evaluated when a graph is compiled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bytes {
    /// No requirement (or an image slot).
    Any,
    /// At least this many.
    AtLeast(&'static str),
    /// Exactly this many: a fixed-size record that the pass writes and the host reads whole
    /// (counters). A larger buffer is refused too, since its tail would mean nothing.
    Exactly(&'static str),
}

impl Bytes {
    /// The expression, if there is a requirement.
    pub fn expr(self) -> Option<&'static str> {
        match self {
            Bytes::Any => None,
            Bytes::AtLeast(e) | Bytes::Exactly(e) => Some(e),
        }
    }
}

/// The size of the first mip of an image a kind creates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Extent {
    /// The output size.
    Output,
    /// The size of the image bound to another slot of the same pass, divided by `divisor` and
    /// rounded down, at least 1 (a pyramid is half its depth: `divisor: 2`).
    Of {
        /// The slot whose image gives the size.
        slot: &'static str,
        /// Divides each dimension.
        divisor: u32,
    },
}

/// Mip levels of an image a kind creates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MipChain {
    /// One level.
    One,
    /// Down to 1x1.
    All,
}

/// What a kind creates for one of its write slots.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Created {
    /// A buffer of the slot's [`Bytes`] (exactly, or at least, as many).
    Buffer,
    /// A buffer of this many bytes (an expression like [`Bytes`]'), where the slot takes any
    /// size a graph declares (a pool whose size is the graph's choice).
    BufferOf(&'static str),
    /// A single-sampled 2D image.
    Image {
        /// Its format.
        format: vk::Format,
        /// The size of its first mip.
        extent: Extent,
        /// Its mips.
        mips: MipChain,
    },
}

/// A resource a kind creates for a write slot, so that graphs declare only what passes share
/// and what the host imports or exports. The graph creates, aliases, reports and checks it like
/// any declared resource, and its errors name the pass at its position.
///
/// When the graph binds the slot to a name it does not declare, the resource gets that name and
/// other passes read it by that name; when the graph leaves the slot unbound, a slot created
/// [`Creates::always`] (a pass's scratch memory, its counters) still gets its resource, named
/// `pass.slot`, which other passes may read by that name too ([`Unbound`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Creates {
    /// What is created.
    pub resource: Created,
    /// Whether last frame's contents stay readable as `name.prev`.
    pub history: bool,
    /// What happens when the graph leaves the slot unbound.
    pub unbound: Unbound,
}

/// Whether a kind creates the resource of a slot that the graph leaves unbound (named
/// `pass.slot`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unbound {
    /// No: the slot stays unbound (the pass does without it).
    Nothing,
    /// Yes: the pass always needs it (scratch memory, counters).
    Create,
    /// When the pass binds this other slot (a part of what that slot turns on).
    CreateWith(&'static str),
}

impl Creates {
    /// A buffer of the slot's size, created when the graph names it.
    pub const fn buffer() -> Self {
        Self { resource: Created::Buffer, history: false, unbound: Unbound::Nothing }
    }

    /// A buffer of `bytes` (an expression), created when the graph names it.
    pub const fn buffer_of(bytes: &'static str) -> Self {
        Self { resource: Created::BufferOf(bytes), history: false, unbound: Unbound::Nothing }
    }

    /// An image, created when the graph names it.
    pub const fn image(format: vk::Format, extent: Extent, mips: MipChain) -> Self {
        Self { resource: Created::Image { format, extent, mips }, history: false, unbound: Unbound::Nothing }
    }

    /// Last frame's contents stay readable as `name.prev`.
    pub const fn history(self) -> Self {
        Self { history: true, ..self }
    }

    /// Created even when the graph leaves the slot unbound (as `pass.slot`).
    pub const fn always(self) -> Self {
        Self { unbound: Unbound::Create, ..self }
    }

    /// Created when the graph leaves the slot unbound but binds `slot` (as `pass.slot`).
    pub const fn with(self, slot: &'static str) -> Self {
        Self { unbound: Unbound::CreateWith(slot), ..self }
    }
}

/// Which frame the counters of a slot describe, and so whose entry of the frame's stats they
/// become.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Counters {
    /// This frame's work of the pass itself.
    ThisFrame,
    /// The list the pass writes for the next frame (as history), which a pass of that frame
    /// draws: reported in the frame that draws it, under the name of the pass that reads the
    /// `.prev` of the resource bound to `count_slot`.
    NextFramesList {
        /// The slot of the list's draw count.
        count_slot: &'static str,
    },
}

/// One named input or output of a pass kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SlotDecl {
    /// Slot name used in the RON `reads`/`writes` maps.
    pub name: &'static str,
    /// How the pass uses what is bound there.
    pub usage: Usage,
    /// Whether the graph must bind it.
    pub required: bool,
    /// Accepted formats (images only).
    pub format: FormatRule,
    /// Whether a multisampled image is accepted (attachments must match the pass's other attachments).
    pub multisample_ok: bool,
    /// What the slot is for, for `graph/README.md`-style listings and errors.
    pub doc: &'static str,
    /// What a buffer bound here must hold; checked when the graph is compiled.
    pub bytes: Bytes,
    /// The resource the kind creates for the slot (write slots only).
    pub creates: Option<Creates>,
    /// The host reads the slot's buffer back after every frame, and the kind decodes it
    /// ([`crate::graph::PassKind::decode_counters`]); the slot's bytes must be `Exactly` a record.
    pub counters: Option<Counters>,
    /// What the buffer holds, where the pass trusts it (`"draw commands"`: a draw reads its
    /// indirect commands from it, and a buffer of anything else could make the device draw
    /// without end). A read slot with a content takes only resources that the host imports or
    /// that are written through slots of the same content.
    pub content: Option<&'static str>,
}

impl SlotDecl {
    /// An optional slot of any format, single-sampled, of any size, that the kind does not create.
    pub const fn new(name: &'static str, usage: Usage, doc: &'static str) -> Self {
        Self {
            name,
            usage,
            required: false,
            format: FormatRule::Any,
            multisample_ok: false,
            doc,
            bytes: Bytes::Any,
            creates: None,
            counters: None,
            content: None,
        }
    }

    /// The graph must bind it.
    pub const fn required(self) -> Self {
        Self { required: true, ..self }
    }

    /// Accepted formats.
    pub const fn format(self, format: FormatRule) -> Self {
        Self { format, ..self }
    }

    /// Multisampled images are accepted.
    pub const fn multisample(self) -> Self {
        Self { multisample_ok: true, ..self }
    }

    /// A buffer of at least `expr` bytes.
    pub const fn at_least(self, expr: &'static str) -> Self {
        Self { bytes: Bytes::AtLeast(expr), ..self }
    }

    /// A buffer of exactly `expr` bytes.
    pub const fn exactly(self, expr: &'static str) -> Self {
        Self { bytes: Bytes::Exactly(expr), ..self }
    }

    /// The kind creates the resource when the graph declares none.
    pub const fn creates(self, creates: Creates) -> Self {
        Self { creates: Some(creates), ..self }
    }

    /// The buffer holds `content` (see [`SlotDecl::content`]).
    pub const fn content(self, content: &'static str) -> Self {
        Self { content: Some(content), ..self }
    }

    /// The slot holds counters that the host reads back every frame.
    pub const fn counters(self, counters: Counters) -> Self {
        Self { counters: Some(counters), ..self }
    }
}
