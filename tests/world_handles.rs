//! Handles belong to their world: another world refuses them, a renderer refuses to sync with
//! a world it was not made from, and a zero or non-finite scale is refused; every refusal is a
//! typed error naming the handle, and nothing is applied. A clone is another world. The
//! README's world example compiles against the prelude as written.

mod common;

use common::{boxes_camera, boxes_scene, GpuTest};
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::world::{World, WorldError};
use cullgraph::scene::{PointLight, Transform};
use glam::{DVec3, Mat3, Vec3};

fn foreign(e: WorldError, a: &World, b: &World) {
    match e {
        WorldError::ForeignHandle { owner, world, ref handle } => {
            assert_eq!((owner, world), (b.id(), a.id()), "{e}");
            assert!(e.to_string().starts_with(handle.as_str()), "{e}");
            assert!(e.to_string().contains(&format!("a handle of world {} given to world {}", b.id(), a.id())), "{e}");
        }
        other => panic!("not a foreign handle: {other}"),
    }
}

#[test]
fn another_worlds_handles_are_refused_by_every_method() {
    let (mut a, ha) = World::new(boxes_scene()).unwrap();
    let (mut b, hb) = World::new(boxes_scene()).unwrap();
    assert_ne!(a.id(), b.id());
    assert_eq!(ha[0].index(), hb[0].index(), "the same index in both worlds");
    let light_b = b.insert_light(PointLight::point(DVec3::Y, Vec3::ONE, 3.0)).unwrap();
    let (version, scene) = (a.version(), a.live_scene());
    let h = hb[0];
    let t = Transform { translation: DVec3::new(1.0, 2.0, 3.0), ..Default::default() };
    foreign(a.instance(h).unwrap_err(), &a, &b);
    foreign(a.remove(h).unwrap_err(), &a, &b);
    foreign(a.set_transform(h, t).unwrap_err(), &a, &b);
    foreign(a.set_transforms(&[(ha[1], t), (h, t)]).unwrap_err(), &a, &b);
    foreign(a.set_transforms_by(&[ha[1], h], |_| t).unwrap_err(), &a, &b);
    let instance = *b.instance(h).unwrap();
    foreign(a.set_instances(&[(h, instance)]).unwrap_err(), &a, &b);
    foreign(a.set_meshes(&[(h, 0)]).unwrap_err(), &a, &b);
    foreign(a.set_materials(&[(h, 0)]).unwrap_err(), &a, &b);
    foreign(a.set_flags(&[(h, 0)]).unwrap_err(), &a, &b);
    foreign(a.set_light(light_b, PointLight::point(DVec3::Y, Vec3::ONE, 3.0)).unwrap_err(), &a, &b);
    foreign(a.remove_light(light_b).unwrap_err(), &a, &b);
    assert_eq!(a.version(), version, "nothing was recorded");
    assert_eq!(a.live_scene().instances, scene.instances, "nothing was applied");
    assert_eq!(a.live_scene().lights, scene.lights);
    // The owner takes them.
    b.set_transform(h, t).unwrap();
    b.remove_light(light_b).unwrap();
}

#[test]
fn a_renderer_refuses_another_world_and_keeps_drawing_its_own() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (a, _) = World::new(boxes_scene()).unwrap();
    let (mut b, hb) = World::new(boxes_scene()).unwrap();
    b.remove(hb[1]).unwrap();
    let mut r =
        Renderer::from_world(&gpu, shaders, &a, RenderSettings::new(64, 48), &GraphSpec::default_graph()).unwrap();
    let before = r.render_to_rgba8(&boxes_camera()).unwrap().1;
    let e = r.sync(shaders, &b).unwrap_err();
    assert!(
        matches!(e, cullgraph::Error::World(WorldError::ForeignWorld { renders, given }) if renders == a.id() && given == b.id()),
        "{e}"
    );
    assert!(e.to_string().contains(&format!("this renderer renders world {}; world {} was given", a.id(), b.id())));
    assert!(r.render_to_rgba8(&boxes_camera()).unwrap().1 == before, "nothing of the other world was applied");
    r.sync(shaders, &a).unwrap();
    gpu.assert_clean();
}

#[test]
fn zero_and_non_finite_scales_are_refused_naming_the_handle() {
    let (mut w, h) = World::new(boxes_scene()).unwrap();
    let version = w.version();
    let flat = |m: Mat3| Transform { linear: m, translation: DVec3::ZERO };
    for bad in [
        flat(Mat3::from_diagonal(Vec3::new(1.0, 0.0, 1.0))),
        flat(Mat3::ZERO),
        flat(Mat3::from_cols(Vec3::X, Vec3::X, Vec3::Z)),
        flat(Mat3::from_diagonal(Vec3::new(1.0, f32::INFINITY, 1.0))),
        flat(Mat3::from_diagonal(Vec3::new(f32::NAN, 1.0, 1.0))),
    ] {
        let e = w.set_transform(h[1], bad).unwrap_err();
        assert!(matches!(e, WorldError::Invalid { .. }), "{e}");
        assert!(e.to_string().starts_with("instance #1 (generation 0): transform"), "{e}");
        let mut instance = *w.instance(h[0]).unwrap();
        instance.transform = bad;
        assert!(matches!(w.insert(instance), Err(WorldError::Invalid { .. })));
    }
    // A mirrored or tiny but invertible scale is fine.
    w.set_transform(h[1], flat(Mat3::from_diagonal(Vec3::new(-1.0, 1e-3, 2.0)))).unwrap();
    assert_eq!(w.version(), version + 1);
}

#[test]
fn a_clone_is_another_world_that_a_renderer_of_the_original_refuses() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (mut a, ha) = World::new(boxes_scene()).unwrap();
    let mut r =
        Renderer::from_world(&gpu, shaders, &a, RenderSettings::new(64, 48), &GraphSpec::default_graph()).unwrap();
    let before = r.render_to_rgba8(&boxes_camera()).unwrap().1;
    let mut copy = a.clone();
    assert_ne!(copy.id(), a.id());
    foreign(copy.remove(ha[1]).unwrap_err(), &copy, &a);
    // The clone changes apart from the original, to the same version: with the original's id
    // the renderer would take it for the original, already synced.
    let own = copy.handle_at(1).unwrap();
    copy.remove(own).unwrap();
    a.set_transform(
        ha[2],
        Transform { translation: DVec3::new(1.5, 1.0, -2.0), ..a.instance(ha[2]).unwrap().transform },
    )
    .unwrap();
    assert_eq!(copy.version(), a.version());
    let e = r.sync(shaders, &copy).unwrap_err();
    assert!(matches!(e, cullgraph::Error::World(WorldError::ForeignWorld { .. })), "{e}");
    assert!(r.render_to_rgba8(&boxes_camera()).unwrap().1 == before, "nothing of the clone was applied");
    r.sync(shaders, &a).unwrap();
    assert!(a.is_live(1), "the original keeps the instance the clone removed");
    gpu.assert_clean();
}

/// The README's world example ("A world that changes"), as written, with only the prelude.
#[test]
fn the_readme_world_example_compiles_against_the_prelude() {
    use cullgraph::prelude::*;
    #[allow(clippy::too_many_arguments)]
    fn readme(
        ctx: GpuContext,
        shaders: ShaderCompiler,
        scene: Scene,
        settings: RenderSettings,
        spec: GraphSpec,
        (moved, turned, transform, mesh_data): (Transform, Transform, Transform, MeshData),
        (width, height, rgba): (u32, u32, Vec<u8>),
    ) -> std::result::Result<UpdateStats, Box<dyn std::error::Error>> {
        let (mesh, material) = (0, 0);
        // From here on the README's lines.
        let (mut world, handles) = World::new(scene)?; // a handle per instance
        let mut renderer = Renderer::from_world(&ctx, &shaders, &world, settings, &spec)?;
        world.set_transforms(&[(handles[3], moved), (handles[7], turned)])?; // f64 translations
        world.set_transforms_by(&handles[4..6], |i| [moved, turned][i])?; // read from the engine's layout
        let car = world.insert(Instance { transform, mesh, material, flags: 0 })?;
        world.remove(handles[9])?; // its handle goes stale
        let mesh = world.add_mesh("truck", &mesh_data)?; // meshes and materials at run time
        world.set_meshes(&[(car, mesh)])?;
        let paint = world.add_texture(Texture { name: "paint".into(), width, height, rgba })?;
        let mut red = Material { name: "red".into(), ..Default::default() };
        red.textures[TextureSlot::BaseColor as usize] = Some(TextureRef::new(paint));
        let red = world.add_material(red)?;
        world.set_materials(&[(car, red)])?; // textured materials too
        let update = renderer.sync(&shaders, &world)?; // before recording the next frame
        Ok(update)
    }
    // Compiling is the point: the other tests render worlds.
    let _ = readme;
}
