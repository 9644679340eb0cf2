//! The size vocabulary is open: a kind that needs a quantity the host does not count yet
//! declares it beside itself ([`PassKind::quantities`]), with the function that counts it in
//! cullgraph's scene description, and graphs and the kind's own sizes use it by name. Nothing
//! of the graph layer knows the name.

use cullgraph::gpu::ShaderRoot;
use cullgraph::graph::{self, NoDevice, ResolvedKind};
use cullgraph::prelude::*;
use cullgraph::scene::procedural;

/// A kind that writes a histogram with a bin per material of the scene.
struct MaterialHistogram;

impl PassKind for MaterialHistogram {
    fn info(&self) -> PassKindInfo {
        PassKindInfo {
            name: "material_histogram",
            doc: "counts the drawn instances of each material",
            reads: vec![],
            writes: vec![SlotDecl::new("bins", Usage::StorageBufferWrite(Stages::Compute), "a count per material")
                .required()
                .at_least("material_bins * 4")
                .creates(Creates::buffer())],
            settings: vec![],
            slots_from_shader: false,
        }
    }

    fn quantities(&self) -> Vec<Quantity> {
        vec![Quantity {
            name: "material_bins",
            doc: "materials of the scene, and one bin for instances without one",
            count: |scene| Some(SceneCounts::downcast(scene)?.scene.materials.len() as u64 + 1),
            growth: Growth::Exact,
        }]
    }

    fn create_node(&self, _: &NodeSetup<'_>) -> cullgraph::Result<Box<dyn PassNode>> {
        Err(cullgraph::Error::Invalid("not recorded in this test".into()))
    }
}

#[test]
fn a_kind_brings_its_own_quantity_and_graphs_use_it_by_name() {
    let mut kinds = builtin_kinds();
    kinds.register(MaterialHistogram).unwrap();
    let text = r#"Graph(
    name: "histogram",
    resources: {"twice": Buffer(size: "material_bins * 8")},
    passes: [
        Pass(name: "first", kind: "material_histogram", writes: {"bins": "bins"}),
        Pass(name: "second", kind: "material_histogram", writes: {"bins": "twice"}),
    ],
    outputs: ["bins", "twice"],
)"#;
    let env = NoDevice::new(ShaderRoot::Embedded).unwrap();
    let g = graph::load(text, "histogram.ron", &[], &env, &kinds).unwrap_or_else(|e| panic!("{e}"));
    let scene =
        procedural::generate("builtin:city", &LoadOptions { instances: Some(100), ..Default::default() }).unwrap();
    let inputs = cullgraph::passes::shared::frame_inputs(&kinds, &scene, 64, 48).unwrap();
    let bins = scene.materials.len() as u64 + 1;
    assert_eq!(inputs.quantities.get("material_bins"), Some(bins));
    let plan = graph::compile(&g, &inputs).unwrap_or_else(|e| panic!("{e}"));
    let bytes = |name: &str| match plan.resources.iter().find(|r| r.name == name).unwrap().kind {
        ResolvedKind::Buffer { size, .. } => size,
        ResolvedKind::Image { .. } => panic!("{name} is a buffer"),
    };
    assert_eq!((bytes("bins"), bytes("twice")), (bins * 4, bins * 8));

    // Without the kind, the name means nothing.
    let err = graph::load(text, "histogram.ron", &[], &env, &builtin_kinds()).unwrap_err().to_string();
    assert!(err.contains("histogram.ron:3:40: size of buffer 'twice': unknown variable 'material_bins'"), "{err}");
}
