//! Test-only pass kinds (no shaders, no device) for compiler tests and property tests: one slot
//! per usage, all optional, any format.

#![allow(dead_code)]

use cullgraph::graph::{KindRegistry, NodeSetup, PassKind, PassKindInfo, PassNode, SlotDecl, Stages, Usage};

const fn slot(name: &'static str, usage: Usage) -> SlotDecl {
    SlotDecl::new(name, usage, "test slot")
}

/// Image read slots of kind `img`.
pub const IMAGE_READS: &[SlotDecl] = &[
    slot("sampled", Usage::Sampled(Stages::Compute)),
    slot("sampled_fs", Usage::Sampled(Stages::Fragment)),
    slot("storage_read", Usage::StorageImageRead(Stages::Compute)),
    slot("transfer_src", Usage::TransferSrc),
];

/// Image write slots of kind `img`.
pub const IMAGE_WRITES: &[SlotDecl] = &[
    slot("storage_write", Usage::StorageImageWrite(Stages::Compute)),
    slot("storage_rw", Usage::StorageImageReadWrite(Stages::Compute)),
    slot("color", Usage::ColorAttachment),
    slot("color_load", Usage::ColorAttachmentLoad),
    slot("transfer_dst", Usage::TransferDst),
];

/// Buffer read slots of kind `buf`.
pub const BUFFER_READS: &[SlotDecl] = &[
    slot("storage_read", Usage::StorageBufferRead(Stages::Compute)),
    slot("storage_read_vs", Usage::StorageBufferRead(Stages::Vertex)),
    slot("uniform", Usage::Uniform(Stages::Compute)),
    slot("indirect", Usage::Indirect),
];

/// Buffer write slots of kind `buf`.
pub const BUFFER_WRITES: &[SlotDecl] = &[
    slot("storage_write", Usage::StorageBufferWrite(Stages::Compute)),
    slot("storage_rw", Usage::StorageBufferReadWrite(Stages::Compute)),
    slot("transfer_dst", Usage::TransferDst),
];

/// A kind that is only declared: graphs using it load and compile, and never run.
struct Declared(PassKindInfo);

impl PassKind for Declared {
    fn info(&self) -> PassKindInfo {
        self.0.clone()
    }

    fn create_node(&self, setup: &NodeSetup<'_>) -> cullgraph::Result<Box<dyn PassNode>> {
        Err(cullgraph::Error::Invalid(format!("test kind of pass '{}' has no node", setup.pass.name)))
    }
}

/// Kind `img` (image slots), `buf` (buffer slots) and `mix` (both, with prefixed names).
pub fn test_kinds() -> KindRegistry {
    let mut kinds = KindRegistry::new();
    // The scene's quantities, as cullgraph's own kinds register them.
    let quantities = cullgraph::passes::shared::scene_quantities();
    for quantity in quantities.into_iter().chain([cullgraph::passes::transparent_sort::BLENDED]) {
        kinds.register_quantity(quantity).expect("distinct quantities");
    }
    for info in test_kind_infos() {
        kinds.register(Declared(info)).expect("distinct test kinds");
    }
    kinds
}

fn test_kind_infos() -> Vec<PassKindInfo> {
    vec![
        PassKindInfo {
            name: "img",
            doc: "image slots",
            reads: IMAGE_READS.to_vec(),
            writes: IMAGE_WRITES.to_vec(),
            settings: vec![],
            slots_from_shader: false,
        },
        PassKindInfo {
            name: "buf",
            doc: "buffer slots",
            reads: BUFFER_READS.to_vec(),
            writes: BUFFER_WRITES.to_vec(),
            settings: vec![],
            slots_from_shader: false,
        },
        PassKindInfo {
            name: "mix",
            doc: "image and buffer slots",
            reads: vec![
                slot("i_sampled", Usage::Sampled(Stages::Compute)),
                slot("i_sampled2", Usage::Sampled(Stages::Compute)),
                slot("i_storage_read", Usage::StorageImageRead(Stages::Compute)),
                slot("b_read", Usage::StorageBufferRead(Stages::Compute)),
                slot("b_indirect", Usage::Indirect),
            ],
            writes: vec![
                slot("i_write", Usage::StorageImageWrite(Stages::Compute)),
                slot("i_write2", Usage::StorageImageWrite(Stages::Compute)),
                slot("i_rw", Usage::StorageImageReadWrite(Stages::Compute)),
                slot("b_write", Usage::StorageBufferWrite(Stages::Compute)),
                slot("b_rw", Usage::StorageBufferReadWrite(Stages::Compute)),
            ],
            settings: vec![],
            slots_from_shader: false,
        },
    ]
}
