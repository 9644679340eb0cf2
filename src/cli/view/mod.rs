//! `cullgraph view`: the renderer in a window. winit owns the window and its events; the
//! [`Viewer`] owns the context, the live world, the renderer and the swapchain, and turns keys,
//! the mouse and `--script` events into camera moves and renderer calls.

mod choices;
mod fly;
mod freeze;
mod keys;
mod present;
mod script;
mod spawns;
mod text;

use super::args::ViewArgs;
use super::paths;
use super::watch::FileWatch;
use choices::GraphChoice;
use cullgraph::gpu::{ContextOptions, GpuContext, ShaderCompiler};
use cullgraph::render::{RenderSettings, Renderer};
use cullgraph::scene::procedural::traffic::Traffic;
use cullgraph::scene::world::World;
use cullgraph::scene::Camera;
use cullgraph::stats::FrameStats;
use cullgraph::{Error, Result};
use fly::FlyCamera;
use keys::Action;
use present::Presenter;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use script::{Event, Script, SCRIPTED_FRAME_SECONDS};
use std::ffi::{CStr, CString};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};
use text::TextPanel;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

/// How often the graph file and shaders are checked for changes.
const POLL: Duration = Duration::from_millis(250);
/// How often the title's figures are refreshed.
const TITLE_EVERY: Duration = Duration::from_millis(250);
/// How long a message stays on screen (errors stay until the next good reload or this long).
const MESSAGE_FOR: Duration = Duration::from_secs(6);

/// Runs the command.
pub fn run(args: &ViewArgs) -> Result<()> {
    let started = Instant::now();
    // What cannot work is refused before a window opens.
    if let Some(shot) = &args.screenshot {
        paths::output_file("--screenshot", shot)?;
    }
    args.gpu.check()?;
    let script = args.script.as_deref().map(Script::load).transpose()?;
    GraphChoice::new(args.graph.as_deref())?.spec(&args.params)?;
    let _: cullgraph::scene::SceneSource = args.scene.scene.parse()?;
    if std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty()) {
        return Err(Error::Invalid(
            "no display: `cullgraph view` opens an X11 window and DISPLAY is not set (on a machine without one, run it under a virtual X server: xvfb-run cullgraph view ...)".into(),
        ));
    }
    let event_loop =
        EventLoop::new().map_err(|e| Error::Invalid(format!("no display: cannot open the window system ({e})")))?;
    let mut app = App { args, script, viewer: None, window: None, outcome: Ok(()), started };
    let ran = event_loop.run_app(&mut app);
    let outcome = std::mem::replace(&mut app.outcome, Ok(()));
    // The swapchain goes before the window it presents to.
    if let Some(viewer) = app.viewer.take() {
        viewer.finish(outcome.is_ok())?;
    }
    drop(app.window.take());
    ran.map_err(|e| Error::Invalid(format!("the window's event loop failed: {e}")))?;
    outcome
}

/// winit's side: the window, and the viewer once the window exists.
struct App<'a> {
    args: &'a ViewArgs,
    script: Option<Script>,
    viewer: Option<Viewer>,
    window: Option<Arc<Window>>,
    /// The first error, which ends the run.
    outcome: Result<()>,
    started: Instant,
}

impl App<'_> {
    fn fail(&mut self, event_loop: &ActiveEventLoop, error: Error) {
        if self.outcome.is_ok() {
            self.outcome = Err(error);
        }
        event_loop.exit();
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let (w, h) = self.args.size;
        let attributes = Window::default_attributes()
            .with_title("cullgraph view")
            .with_inner_size(winit::dpi::PhysicalSize::new(w, h));
        let window = Arc::new(
            event_loop.create_window(attributes).map_err(|e| Error::Invalid(format!("cannot open a window: {e}")))?,
        );
        self.window = Some(window.clone());
        let viewer = Viewer::new(self.args, window, self.script.take(), self.started)?;
        self.viewer = Some(viewer);
        Ok(())
    }
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        if let Err(e) = self.open(event_loop) {
            self.fail(event_loop, e);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(viewer) = self.viewer.as_mut() else { return };
        let outcome = match event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::RedrawRequested => match viewer.frame() {
                Ok(true) => Ok(()),
                Ok(false) => {
                    event_loop.exit();
                    Ok(())
                }
                Err(e) => Err(e),
            },
            other => {
                viewer.window_event(other);
                if viewer.quit {
                    event_loop.exit();
                }
                Ok(())
            }
        };
        if let Err(e) = outcome {
            self.fail(event_loop, e);
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let (Some(viewer), Some(window)) = (&self.viewer, &self.window) else { return };
        if viewer.presenter.can_present() {
            event_loop.set_control_flow(ControlFlow::Poll);
            window.request_redraw();
        } else {
            // Minimised: nothing to draw until the window has an area again.
            event_loop.set_control_flow(ControlFlow::Wait);
        }
    }
}

/// The scene in a window, and everything the keys change.
struct Viewer {
    args: ViewArgs,
    window: Arc<Window>,
    ctx: GpuContext,
    shaders: ShaderCompiler,
    world: World,
    /// The city's traffic, made when first turned on (its vehicles join the world then).
    traffic: Option<Traffic>,
    traffic_on: bool,
    is_city: bool,
    /// The city's instances before any vehicle (the traffic is sized by them).
    city_instances: usize,
    renderer: Renderer,
    presenter: Presenter,
    fly: FlyCamera,
    spawns: Vec<spawns::Spawn>,
    spawn: usize,
    graphs: GraphChoice,
    shadows: bool,
    /// The sample count before M rebuilt the graph, until the new one presented a frame.
    msaa_untried: Option<Option<u32>>,
    frozen: Option<freeze::Frozen>,
    script: Option<Script>,
    help: bool,
    /// A line on screen, whether it is an error, and since when.
    message: Option<(String, bool, Instant)>,
    files: FileWatch,
    polled: Instant,
    /// Frames presented, and those of them whose figures came back.
    presented: u64,
    last_stats: Option<FrameStats>,
    /// Wall-clock milliseconds between presents, smoothed, and the last present.
    frame_ms: f64,
    last_present: Option<Instant>,
    /// Sum and count of the frame times after the first few (for the summary).
    frame_ms_sum: (f64, u64),
    titled: Instant,
    started: Instant,
    first_frame: Option<Duration>,
    looking: bool,
    cursor: Option<(f64, f64)>,
    shift: bool,
    screenshots: u32,
    screenshot_wanted: bool,
    quit: bool,
}

impl Viewer {
    fn new(args: &ViewArgs, window: Arc<Window>, script: Option<Script>, started: Instant) -> Result<Self> {
        let display = window.display_handle().map_err(|e| Error::Invalid(format!("no display handle: {e}")))?.as_raw();
        let handle = window.window_handle().map_err(|e| Error::Invalid(format!("no window handle: {e}")))?.as_raw();
        let instance_extensions = ash_window::enumerate_required_extensions(display)
            .map_err(|e| Error::Invalid(format!("this window system has no Vulkan surface extension ({e})")))?
            .iter()
            // SAFETY: ash-window returns pointers to static NUL-terminated extension names.
            .map(|&p| unsafe { CStr::from_ptr(p) }.to_owned())
            .collect();
        let ctx = GpuContext::new(&ContextOptions {
            instance_extensions,
            device_extensions: vec![CString::from(ash::khr::swapchain::NAME)],
            ..args.gpu.context_options("cullgraph view")
        })?;
        let size = window.inner_size();
        let (width, height) = (size.width.max(1), size.height.max(1));
        let presenter = Presenter::new(&ctx, display, handle, (width, height), args.vsync)?;
        let (width, height) = match presenter.extent() {
            (0, _) | (_, 0) => (width, height),
            extent => extent,
        };
        let scene = args.scene.load()?;
        let start = start_camera(args, &scene, width as f32 / height as f32)?;
        let spawns = spawns::spawns(&args.scene.scene, &scene, &start, args.spawns.as_deref())?;
        let speed = FlyCamera::speed_for(scene.world_bounds().map_or(100.0, |(lo, hi)| (hi - lo).length()));
        let is_city = scene.name == "builtin:city";
        if args.animate && !is_city {
            return Err(Error::Invalid(format!(
                "--animate drives traffic through builtin:city, not {}",
                args.scene.scene
            )));
        }
        let instances = scene.instances.len();
        let (world, _) = World::new(scene)?;
        let shaders = args.gpu.shaders()?;
        let mut graphs = GraphChoice::new(args.graph.as_deref())?;
        graphs.overlay = args.overlay;
        let spec = graphs.spec(&args.params)?;
        let mut renderer = Renderer::from_world(&ctx, &shaders, &world, RenderSettings::new(width, height), &spec)?;
        let shadows = args.shadows;
        renderer.set_shadows(&shaders, shadow_settings(args, shadows))?;
        let files = FileWatch::new(super::render::watched_paths(args.graph.as_deref(), &renderer, &shaders));
        let now = Instant::now();
        let mut viewer = Self {
            args: args.clone(),
            window,
            ctx,
            shaders,
            world,
            traffic: None,
            traffic_on: false,
            is_city,
            city_instances: instances,
            renderer,
            presenter,
            fly: FlyCamera::new(start, speed),
            spawns,
            spawn: 0,
            graphs,
            shadows,
            msaa_untried: None,
            frozen: None,
            script,
            help: false,
            message: None,
            files,
            polled: now,
            presented: 0,
            last_stats: None,
            frame_ms: 0.0,
            last_present: None,
            frame_ms_sum: (0.0, 0),
            titled: now,
            started,
            first_frame: None,
            looking: false,
            cursor: None,
            shift: false,
            screenshots: 0,
            screenshot_wanted: false,
            quit: false,
        };
        if args.animate {
            viewer.toggle_traffic()?;
            viewer.message = None;
        }
        viewer.update_title();
        println!(
            "view: {} ({} instances) through '{}' on {}, presenting {:?}; H in the window lists the keys",
            viewer.args.scene.scene,
            instances,
            viewer.renderer.plan().name,
            viewer.ctx.caps().name,
            viewer.presenter.present_mode()
        );
        Ok(viewer)
    }

    /// Renders and presents one frame; `false` once the run is over (`--frames`).
    fn frame(&mut self) -> Result<bool> {
        let scripted = self.script.is_some() || self.args.frames.is_some();
        let now = Instant::now();
        let seconds = match (scripted, self.last_present) {
            (true, _) | (false, None) => SCRIPTED_FRAME_SECONDS,
            (false, Some(last)) => now.duration_since(last).as_secs_f64(),
        };
        if let Some(script) = self.script.as_mut() {
            for event in script.due(self.presented) {
                self.play(event)?;
            }
        }
        self.fly.step(seconds);
        if self.traffic_on {
            if let Some(traffic) = self.traffic.as_mut() {
                traffic.step(&mut self.world, seconds)?;
            }
        }
        self.renderer.sync(&self.shaders, &self.world)?;
        self.world.trim_journal(self.renderer.synced_version().unwrap_or(0));
        if now.duration_since(self.polled) >= POLL {
            self.polled = now;
            if self.files.changed() {
                self.reload("a file changed");
            }
        }
        if !self.presenter.can_present() {
            return Ok(true);
        }
        self.presenter.prepare()?;
        let (w, h) = self.presenter.extent();
        let settings = self.renderer.settings();
        if w > 0 && h > 0 && (settings.width, settings.height) != (w, h) {
            self.renderer.resize(&self.shaders, w, h)?;
        }
        let last = self.args.frames.is_some_and(|n| self.presented + 1 >= n as u64);
        let screenshot = std::mem::take(&mut self.screenshot_wanted) || (last && self.args.screenshot.is_some());
        let panels = self.panels();
        let panel_refs: Vec<&TextPanel> = panels.iter().collect();
        let camera = self.fly.camera();
        let presented = self.presenter.present(&mut self.renderer, &camera, &panel_refs, screenshot);
        let presented = match presented {
            Ok(p) => p,
            Err(e) if self.graphs.reloaded_untried => {
                // The new graph compiled but could not record its first frame: the last good one
                // comes back.
                self.renderer.revert_reload()?;
                self.graphs.revert();
                self.show_error(&format!("{e}\n(back to the last good graph)"));
                return Ok(true);
            }
            Err(e) if self.msaa_untried.is_some() => {
                self.renderer.revert_reload()?;
                self.graphs.msaa = self.msaa_untried.take().flatten();
                self.show_error(&format!("{e}\n(back to the last good sample count)"));
                return Ok(true);
            }
            Err(e) => return Err(e),
        };
        if let Some(frame) = presented.completed {
            self.last_stats = Some(self.renderer.completed_stats(frame)?);
        }
        if presented.frame.is_none() {
            if screenshot {
                self.screenshot_wanted = true;
            }
            return Ok(true);
        }
        self.graphs.reloaded_untried = false;
        self.msaa_untried = None;
        self.presented += 1;
        let now = Instant::now();
        if let Some(previous) = self.last_present {
            let ms = now.duration_since(previous).as_secs_f64() * 1e3;
            self.frame_ms = if self.frame_ms == 0.0 { ms } else { self.frame_ms * 0.9 + ms * 0.1 };
            if self.presented > 3 {
                self.frame_ms_sum.0 += ms;
                self.frame_ms_sum.1 += 1;
            }
        }
        self.last_present = Some(now);
        self.first_frame.get_or_insert_with(|| self.started.elapsed());
        if let Some((w, h, rgba)) = presented.screenshot {
            self.save_screenshot(w, h, rgba, last)?;
        }
        if now.duration_since(self.titled) >= TITLE_EVERY {
            self.titled = now;
            self.update_title();
        }
        Ok(!last)
    }

    fn window_event(&mut self, event: WindowEvent) {
        let outcome = match event {
            WindowEvent::Resized(size) => {
                self.presenter.resize(size.width, size.height);
                Ok(())
            }
            WindowEvent::Focused(false) => {
                self.fly.release_all();
                self.looking = false;
                Ok(())
            }
            WindowEvent::ModifiersChanged(modifiers) => {
                self.shift = modifiers.state().shift_key();
                self.fly.hold_fast(self.shift);
                Ok(())
            }
            WindowEvent::KeyboardInput { event, .. } => {
                let down = event.state == ElementState::Pressed;
                match keys::key_name(&event.logical_key).and_then(|n| keys::action_named(&n)) {
                    // A held key repeats: only movement cares, and it is already held.
                    Some(action) if !event.repeat => self.act(action, down),
                    _ => Ok(()),
                }
            }
            WindowEvent::MouseInput { state, .. } => {
                self.looking = state == ElementState::Pressed;
                Ok(())
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let (true, Some((x, y))) = (self.looking, self.cursor) {
                    self.fly.turn(position.x - x, position.y - y);
                }
                self.cursor = Some((position.x, position.y));
                Ok(())
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let notches = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y as f64,
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
                self.wheel(notches);
                Ok(())
            }
            _ => Ok(()),
        };
        if let Err(e) = outcome {
            self.show_error(&e.to_string());
        }
    }

    fn wheel(&mut self, notches: f64) {
        self.fly.scale_speed(1.25f64.powf(notches.clamp(-20.0, 20.0)));
        self.show_info(&format!("flying at {:.3} units/s", self.fly.speed()));
    }

    /// Plays one scripted event as the window would have delivered it.
    fn play(&mut self, event: Event) -> Result<()> {
        match event {
            Event::Key(action, down) => self.act(action, down)?,
            Event::Look(dx, dy) => self.fly.turn(dx, dy),
            Event::Wheel(notches) => self.wheel(notches),
            Event::Resize(w, h) => {
                // The window manager (if any) decides; the Resized event follows.
                if let Some(size) = self.window.request_inner_size(winit::dpi::PhysicalSize::new(w, h)) {
                    self.presenter.resize(size.width, size.height);
                }
            }
        }
        Ok(())
    }

    /// What a key does, going down (`down`) or up.
    fn act(&mut self, action: Action, down: bool) -> Result<()> {
        match action {
            Action::Move(movement) => {
                self.fly.hold(movement, down);
                return Ok(());
            }
            Action::Shift => {
                self.shift = down;
                self.fly.hold_fast(down);
                return Ok(());
            }
            _ if !down => return Ok(()),
            _ => {}
        }
        match action {
            Action::Help => self.help = !self.help,
            Action::Quit => self.quit = true,
            Action::Overlay => {
                self.graphs.overlay = !self.graphs.overlay;
                let on = self.graphs.overlay;
                self.apply_graph(if on { "overlay on" } else { "overlay off" });
            }
            Action::OverlayView => {
                self.graphs.next_overlay_view();
                self.graphs.overlay = true;
                let what = format!("overlay view {}", self.graphs.overlay_view());
                self.apply_graph(&what);
            }
            Action::NextGraph | Action::PreviousGraph => {
                let back = action == Action::PreviousGraph || self.shift;
                self.graphs.step(if back { -1 } else { 1 });
                self.apply_graph("graph");
            }
            Action::Msaa => self.next_msaa(),
            Action::Shadows => {
                self.shadows = !self.shadows;
                match self.renderer.set_shadows(&self.shaders, shadow_settings(&self.args, self.shadows)) {
                    Ok(()) => self.show_info(if self.shadows { "shadows on" } else { "shadows off" }),
                    Err(e) => {
                        self.shadows = !self.shadows;
                        self.show_error(&e.to_string());
                    }
                }
            }
            Action::Freeze => self.toggle_freeze()?,
            Action::Traffic => self.toggle_traffic()?,
            Action::Reload => self.reload("R"),
            Action::Screenshot => self.screenshot_wanted = true,
            Action::NextSpawn => {
                let n = self.spawns.len();
                self.spawn = if self.shift { (self.spawn + n - 1) % n } else { (self.spawn + 1) % n };
                let spawn = &self.spawns[self.spawn];
                self.fly.look_at(&spawn.camera);
                let line = format!("{} ({}/{})", spawn.name, self.spawn + 1, n);
                self.show_info(&line);
            }
            Action::Move(_) | Action::Shift => {}
        }
        Ok(())
    }

    /// Loads the graph the choice now names; on error the running graph stays and the choice
    /// goes back.
    fn apply_graph(&mut self, what: &str) {
        let applied =
            self.graphs.spec(&self.args.params).and_then(|spec| self.renderer.reload_graph(&self.shaders, &spec));
        match applied {
            Ok(()) => {
                self.graphs.accepted();
                self.files.watch_also(super::render::watched_paths(self.graphs.file(), &self.renderer, &self.shaders));
                let line = format!("{what}: '{}'", self.renderer.plan().name);
                self.show_info(&line);
            }
            Err(_) if self.graphs.overlay => {
                // The overlay reads two-phase culling's counters and pyramid: over a graph
                // without them, the graph alone.
                self.graphs.overlay = false;
                self.apply_graph(what);
                if !self.graphs.overlay && self.message.as_ref().is_some_and(|(_, error, _)| !error) {
                    let line = format!(
                        "{what}: '{}' (overlay off: it reads two-phase culling's cull_late and hiz, which this graph lacks)",
                        self.renderer.plan().name
                    );
                    self.show_info(&line);
                }
            }
            Err(e) => {
                self.graphs.revert();
                self.show_error(&format!("{what}: {e}\n(still running '{}')", self.renderer.plan().name));
            }
        }
    }

    /// Reloads the graph and its shaders from disk (`why` says what asked for it).
    fn reload(&mut self, why: &str) {
        self.shaders.clear_cache();
        let applied =
            self.graphs.spec(&self.args.params).and_then(|spec| self.renderer.reload_graph(&self.shaders, &spec));
        match applied {
            Ok(()) => {
                self.graphs.accepted();
                let line = format!("reloaded '{}' ({why})", self.renderer.plan().name);
                println!("{line}");
                self.show_info(&line);
            }
            Err(e) => self.show_error(&format!("{e}\n(still running the last good graph)")),
        }
        // Headers a changed shader now includes.
        self.files.watch_also(super::render::watched_paths(self.graphs.file(), &self.renderer, &self.shaders));
    }

    /// The running graph's next MSAA sample count the device supports, through its `msaa` param.
    fn next_msaa(&mut self) {
        let counts = msaa_counts(&self.ctx);
        let Some(&next) = counts.iter().find(|&&n| n > self.graphs.msaa.unwrap_or(0)).or(counts.first()) else {
            return self.show_error("the device has no multisampled targets");
        };
        let value = next.to_string();
        match self.renderer.set_graph_params(&self.shaders, &[("msaa", &value)]) {
            Ok(_) => {
                self.msaa_untried = Some(self.graphs.msaa);
                self.graphs.msaa = Some(next);
                self.show_info(&format!("MSAA {next}x"));
            }
            Err(e) => self.show_error(&format!(
                "MSAA: {e}\n(the MSAA graphs take it: G to msaa_compressed, msaa_per_sample, ...)"
            )),
        }
    }

    fn toggle_traffic(&mut self) -> Result<()> {
        if !self.is_city {
            self.show_error("traffic drives through builtin:city only");
            return Ok(());
        }
        if self.traffic.is_none() {
            let vehicles = (self.city_instances / 50).max(20);
            let churn = vehicles as f64 / 20.0;
            let seed = self.args.scene.seed;
            self.traffic = Some(Traffic::new(&mut self.world, self.city_instances, vehicles, churn, seed)?);
        }
        self.traffic_on = !self.traffic_on;
        self.show_info(if self.traffic_on { "traffic on" } else { "traffic off" });
        Ok(())
    }

    fn toggle_freeze(&mut self) -> Result<()> {
        match self.frozen.take() {
            Some(frozen) => {
                self.presenter.finish()?;
                let shown = frozen.thaw(&mut self.world)?;
                let line = format!("culling follows the camera again ({shown} instances back)");
                println!("{line}");
                self.show_info(&line);
            }
            None => {
                self.presenter.finish()?;
                let camera = self.fly.camera();
                let frozen = freeze::Frozen::capture(&mut self.world, &mut self.renderer, &self.shaders, &camera)?;
                let line = format!(
                    "culling frozen: the {} instances drawn from here stay, {} culled ones are hidden; F again to thaw",
                    frozen.kept(),
                    frozen.hidden()
                );
                println!("{line}");
                self.show_info(&line);
                self.frozen = Some(frozen);
            }
        }
        Ok(())
    }

    fn show_info(&mut self, line: &str) {
        self.message = Some((line.to_string(), false, Instant::now()));
    }

    fn show_error(&mut self, error: &str) {
        eprintln!("error: {error}");
        self.message = Some((error.to_string(), true, Instant::now()));
    }

    /// The text panels over the frame: the help, and the message of the moment.
    fn panels(&mut self) -> Vec<TextPanel> {
        let (w, h) = self.presenter.extent();
        let scale = (h / 720).max(1);
        let mut panels = Vec::new();
        if self.help {
            let mut lines = vec![("cullgraph view: keys".to_string(), text::YELLOW)];
            lines.extend(keys::HELP.iter().map(|(k, what)| (format!("{k:<16} {what}"), text::WHITE)));
            lines.push((String::new(), text::WHITE));
            lines.push((format!("graph: {}", self.renderer.plan().name), text::YELLOW));
            // Top right: the culling-stat overlay's panel is top left.
            let mut panel = TextPanel::new(&lines, 0, 8 * scale, scale);
            panel.x = w.saturating_sub(panel.size().0 + 8 * scale);
            panels.push(panel);
        }
        if self.message.as_ref().is_some_and(|(_, _, since)| since.elapsed() > MESSAGE_FOR) {
            self.message = None;
        }
        if let Some((message, error, _)) = &self.message {
            let colour = if *error { text::RED } else { text::WHITE };
            let lines: Vec<(String, [u8; 3])> =
                message.lines().flat_map(|l| wrap(l, 100)).map(|l| (l, colour)).take(12).collect();
            let mut panel = TextPanel::new(&lines, 0, 0, scale);
            let (_, ph) = panel.size();
            panel.x = 8 * scale;
            panel.y = h.saturating_sub(ph + 8 * scale);
            panels.push(panel);
        }
        panels
    }

    fn update_title(&self) {
        let mut title = format!("cullgraph view: {} through '{}'", self.args.scene.scene, self.renderer.plan().name);
        if self.frame_ms > 0.0 {
            title.push_str(&format!(" | {:.1} ms ({:.0} fps)", self.frame_ms, 1e3 / self.frame_ms));
        }
        if let Some(s) = &self.last_stats {
            title.push_str(&format!(
                " | GPU {:.2} ms | {} drawn, {} culled ({} frustum, {} occlusion)",
                s.gpu_total_ms,
                s.drawn,
                s.frustum_culled + s.occlusion_culled,
                s.frustum_culled,
                s.occlusion_culled
            ));
        }
        if self.frozen.is_some() {
            title.push_str(" | culling frozen");
        }
        title.push_str(" | H: help");
        self.window.set_title(&title);
    }

    fn save_screenshot(&mut self, w: u32, h: u32, rgba: Vec<u8>, last: bool) -> Result<()> {
        let path = match (&self.args.screenshot, last) {
            (Some(path), true) => path.clone(),
            _ => {
                self.screenshots += 1;
                let n = self.screenshots;
                match &self.args.screenshot {
                    Some(path) => path.with_extension(format!("{n}.png")),
                    None => PathBuf::from(format!("out/view-{n}.png")),
                }
            }
        };
        paths::output_file("--screenshot", &path)?;
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|source| Error::Io { path: dir.display().to_string(), source })?;
        }
        let image = cullgraph::render::output::rgba_from_bytes(w, h, rgba)?;
        cullgraph::render::output::save_png(&image, &path)?;
        println!("screenshot ({w}x{h}) -> {}", path.display());
        if !last {
            self.show_info(&format!("screenshot -> {}", path.display()));
        }
        Ok(())
    }

    /// Waits for the last frames, prints the run's figures, and checks the validation layer.
    fn finish(mut self, print: bool) -> Result<()> {
        for frame in self.presenter.finish()? {
            self.last_stats = Some(self.renderer.completed_stats(frame)?);
        }
        if print {
            let (sum, n) = self.frame_ms_sum;
            let mean = if n > 0 { format!("{:.2} ms", sum / n as f64) } else { "-".into() };
            let first = self.first_frame.map_or("-".into(), |d| format!("{:.0} ms", d.as_secs_f64() * 1e3));
            let (w, h) = self.presenter.extent();
            print!("view: {} frames presented at {w}x{h}, mean frame {mean} (after the first 3), first frame {first} after start", self.presented);
            match &self.last_stats {
                Some(s) => println!(
                    "; last: {} drawn, {} frustum-culled, {} occlusion-culled, GPU {:.3} ms",
                    s.drawn, s.frustum_culled, s.occlusion_culled, s.gpu_total_ms
                ),
                None => println!(),
            }
            let c = self.fly.camera();
            println!(
                "view: camera eye={:.4},{:.4},{:.4} target={:.4},{:.4},{:.4}, flying at {:.4} units/s",
                c.eye.x,
                c.eye.y,
                c.eye.z,
                c.target.x,
                c.target.y,
                c.target.z,
                self.fly.speed()
            );
        }
        let messages = self.ctx.validation_log().count();
        drop(self.presenter);
        drop(self.renderer);
        if messages > 0 {
            return Err(Error::Invalid(format!("the validation layer reported {messages} message(s)")));
        }
        Ok(())
    }
}

/// The camera the viewer starts at: `--eye`/`--target`/`--fov`/`--near` over the scene's
/// default view.
fn start_camera(args: &ViewArgs, scene: &cullgraph::scene::Scene, aspect: f32) -> Result<Camera> {
    let camera = args.camera.apply(scene.default_camera(aspect));
    camera.validate().map_err(|e| Error::Invalid(format!("camera: {e}")))?;
    Ok(camera)
}

fn shadow_settings(args: &ViewArgs, on: bool) -> Option<cullgraph::render::ShadowSettings> {
    on.then(|| cullgraph::render::ShadowSettings { cascades: args.cascades, ..Default::default() })
}

/// The MSAA sample counts above one that the device renders colour and depth with.
fn msaa_counts(ctx: &GpuContext) -> Vec<u32> {
    // SAFETY: valid handles.
    let limits = unsafe { ctx.instance().get_physical_device_properties(ctx.physical_device()) }.limits;
    let both = limits.framebuffer_color_sample_counts & limits.framebuffer_depth_sample_counts;
    [2u32, 4, 8].into_iter().filter(|&n| both.contains(ash::vk::SampleCountFlags::from_raw(n))).collect()
}

/// `line` cut into pieces of at most `width` characters.
fn wrap(line: &str, width: usize) -> Vec<String> {
    let chars: Vec<char> = line.chars().collect();
    if chars.is_empty() {
        return vec![String::new()];
    }
    chars.chunks(width).map(|c| c.iter().collect()).collect()
}
