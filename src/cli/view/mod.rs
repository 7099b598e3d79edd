//! `lacuna view`: an interactive window on a volume. The viewer is a host
//! like any engine (`host`: its own instance, device, swapchain) that adopts
//! its device into lacuna (`scene`: the renderer's use, in one module);
//! `controls` turns mouse and keys into camera, TF and structure changes;
//! `title` says what the window shows; `window` holds winit's side.

mod blit;
mod controls;
mod host;
mod keys;
mod look;
mod scene;
mod tf_shape;
mod title;
mod window;

use super::args::{AccelParser, FrameArgs, ModelArgs};
use super::{check_parent, tf_for, validation_verdict, VolumeArgs};
use clap::Args;
use controls::Controls;
use host::Host;
use lacuna::accel::Accel;
use lacuna::frame::{Frame, FrameFormat};
use lacuna::render::{self, Filter, FrameDesc};
use lacuna::volume::Series;
use lacuna::{Error, Result, TransferFunction};
use scene::Scene;
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Instant;
use window::{end_on_signals, fit, is_modifier, without_source_location, Signalled};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, ModifiersState};
use winit::window::{Window, WindowId};

#[derive(Args)]
pub struct ViewArgs {
    #[command(flatten)]
    volume: VolumeArgs,
    /// Transfer function: ramp:LO:HI[:A], band:LO:HI[:A], spike:C:W[:A] or a ParaView .json (default: the generator's).
    /// Several channels: one --tf per channel in order, or one for all.
    #[arg(long)]
    tf: Vec<TransferFunction>,
    /// Empty space skipping structure to start with (Tab switches).
    #[arg(long, default_value = "auto", value_parser = AccelParser)]
    accel: Accel,
    /// A ParaView JSON colormap the J key loads (read again on every press).
    #[arg(long)]
    json: Option<PathBuf>,
    /// Window (and frame) size WxH.
    #[arg(long, default_value = "512x512", value_parser = render::parse_size, allow_hyphen_values = true)]
    size: (u32, u32),
    #[command(flatten)]
    frame: FrameArgs,
    #[command(flatten)]
    model: ModelArgs,
    /// Render this many frames, then exit (for tests and scripts).
    #[arg(long)]
    frames: Option<u32>,
    /// With --frames: write the last frame here (.exr: linear RGBA f32 as rendered; .png). The S key writes NAME-1.exr and NAME-1.png, then -2, ...
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// Keys to press before the first frame, comma-separated by name (t, Tab, Shift+Tab, ArrowLeft, Comma for ',', ...), for scripts and tests; `frame` draws a frame before the keys after it; q or Escape ends the session.
    #[arg(long, value_delimiter = ',', value_parser = controls::script_key)]
    keys: Vec<String>,
    /// Enable Vulkan validation with synchronization validation; fail on any message.
    #[arg(long)]
    validate: bool,
}

/// In `--keys`, a frame drawn before the keys after it.
const FRAME_KEY: &str = "frame";
/// Keys that end the session.
const QUIT_KEYS: [&str; 2] = ["q", "Escape"];

/// Everything the window needs; dropped in field order (lacuna before the host's device, the window last).
struct Viewer {
    scene: Scene,
    host: Host,
    window: Window,
    controls: Controls,
    filter: Filter,
    resize: bool,
    drawn: u32,
    /// Scripted keys not pressed yet: those after a `frame` (`--keys`).
    pending_keys: VecDeque<String>,
    /// A scripted Esc or Q was pressed: the session ends.
    quit: bool,
    /// Screenshots asked for by the S key since the last frame, and in all.
    shots: u32,
    shots_written: u32,
    /// The last frame's end, when the next one followed at once (an idle
    /// wait is no frame interval), and the frame rate over such intervals.
    last: Option<Instant>,
    fps: f64,
    /// The last frame's wall time, from its draw to its present, ms.
    frame_ms: f64,
    /// Something on screen changed since the last frame: draw one. An
    /// unchanged window is not redrawn (`wants_frame`).
    dirty: bool,
    /// This frame redraws one presented to a stale swapchain.
    stale_redraw: bool,
    modifiers: ModifiersState,
    cursor: Option<(f64, f64)>,
    buttons: (bool, bool),
    /// What the last key's rebuild failed with.
    key_result: Option<Error>,
    /// The volume's time steps, the step on the GPU, and the next step
    /// loading on a host thread while this one renders (when playing).
    series: Arc<Series>,
    shown: u32,
    prefetch: Option<(u32, Loading)>,
    /// The last step's host load (read or generate), ms.
    load_ms: f64,
}

/// A time step and how long its host load took, ms.
type LoadedStep = (lacuna::Volume, f64);

/// A time step loading on a host thread.
type Loading = JoinHandle<Result<LoadedStep>>;

struct App<'a> {
    args: &'a ViewArgs,
    /// The series, its first step and how long that took to load, its TF
    /// and the first frame.
    setup: Option<(Arc<Series>, LoadedStep, TransferFunction, FrameDesc)>,
    viewer: Option<Viewer>,
    error: Option<Error>,
}

impl ViewArgs {
    /// The first frame, every option checked.
    fn desc(&self) -> Result<FrameDesc> {
        let desc = self.frame.desc(self.size)?;
        if self.frames == Some(0) {
            return Err(Error::invalid("frames", "0", "must be at least 1"));
        }
        if let Some(path) = &self.screenshot {
            FrameFormat::from_path(path)?;
            check_parent(path)?;
        }
        if let Some(json) = &self.json {
            TransferFunction::from_paraview_json(json)?;
        }
        if let Some(key) = self.keys.iter().find(|k| *k != FRAME_KEY && !controls::known_key(k)) {
            return Err(Error::invalid(
                "key",
                key.clone(),
                format!("expected one of: {}, or {FRAME_KEY}", controls::script_names()),
            ));
        }
        self.check_key_script()?;
        Ok(desc)
    }
}

pub fn run(args: &ViewArgs) -> Result<ExitCode> {
    let desc = args.desc()?;
    let series = Arc::new(args.volume.series()?);
    let loading = Instant::now();
    let volume = series.load(args.volume.time, None)?;
    let load_ms = loading.elapsed().as_secs_f64() * 1000.0;
    let tf = tf_for(&args.tf, &volume)?.unwrap_or(TransferFunction::parse("ramp:0:1")?);
    desc.check_for(volume.dims, volume.spacing)?;
    for note in super::render::look_notes(&desc) {
        say_err!("note: {note}");
    }
    if let Some(note) = series.norm_note() {
        say_err!("note: {note}");
    }
    let event_loop = EventLoop::with_user_event().build().map_err(|e| {
        let e = without_source_location(&e.to_string());
        Error::NoDevice(format!(
            "cannot open a window ({e}); set DISPLAY, or run under xvfb-run"
        ))
    })?;
    // Frames are drawn when asked for (`Viewer::wants_frame`), so an idle
    // window waits for events rather than spinning.
    event_loop.set_control_flow(ControlFlow::Wait);
    end_on_signals(&event_loop);
    let mut app = App {
        args,
        setup: Some((series, (volume, load_ms), tf, desc)),
        viewer: None,
        error: None,
    };
    let ran = event_loop.run_app(&mut app);
    let Some(viewer) = app.viewer.take() else {
        return Err(app
            .error
            .unwrap_or_else(|| Error::NoDevice("the window closed before it opened".into())));
    };
    // However the session ended (--frames, Q, Esc, the window closed,
    // Ctrl-C), the title's figures.
    if app.error.is_none() {
        say!("{}", viewer.summary());
    }
    // lacuna's objects go first, then the host's window objects, while the
    // adopted context still collects validation messages; then the device.
    let Viewer {
        scene,
        mut host,
        window,
        ..
    } = viewer;
    let ctx = scene.context().clone();
    drop(scene);
    host.release();
    let verdict = validation_verdict(&ctx);
    drop(ctx);
    drop(host);
    drop(window);
    if let Some(e) = app.error {
        return Err(e);
    }
    ran.map_err(|e| {
        Error::NoDevice(format!(
            "window event loop failed: {}",
            without_source_location(&e.to_string())
        ))
    })?;
    Ok(verdict)
}

impl App<'_> {
    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let Some((series, (volume, first_load_ms), tf, desc)) = self.setup.take() else {
            return Ok(());
        };
        let (width, height) = desc.size();
        let attributes = Window::default_attributes()
            .with_title("lacuna view")
            .with_inner_size(PhysicalSize::new(width, height));
        let window = event_loop.create_window(attributes).map_err(|e| {
            Error::NoDevice(format!(
                "cannot open a window: {}",
                without_source_location(&e.to_string())
            ))
        })?;
        let host = Host::new(&window, self.args.validate)?;
        let ctx = host.adopt(self.args.validate)?;
        // The frame's size against the device's limits, before the canvas.
        lacuna::render::RenderTarget::check_size(ctx.info(), width, height)?;
        let builder = self.args.model.builder(&ctx)?;
        let scene = Scene::new(
            builder,
            volume,
            tf.clone(),
            self.args.accel,
            *desc.mode(),
            (desc.filter(), self.args.volume.storage),
        )?;
        let filter = match desc.filter() {
            Some(filter) => filter,
            None => scene.default_filter()?,
        };
        let json = self.args.json.as_ref().map(|p| p.display().to_string());
        let mut controls = Controls::new(&desc, &tf.spec, self.args.accel, json);
        controls.steps = series.steps();
        controls.time = self.args.volume.time;
        self.viewer = Some(Viewer {
            scene,
            host,
            window,
            controls,
            filter,
            resize: true,
            drawn: 0,
            pending_keys: VecDeque::new(),
            quit: false,
            shots: 0,
            shots_written: 0,
            last: None,
            fps: 0.0,
            frame_ms: 0.0,
            dirty: true,
            stale_redraw: false,
            modifiers: ModifiersState::empty(),
            cursor: None,
            buttons: (false, false),
            key_result: None,
            shown: self.args.volume.time,
            series,
            prefetch: None,
            load_ms: first_load_ms,
        });
        if let Some(viewer) = self.viewer.as_mut() {
            viewer.pending_keys = self.args.keys.iter().cloned().collect();
            viewer.press_pending()?;
            if viewer.quit {
                event_loop.exit();
            }
        }
        Ok(())
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: Error) {
        self.error.get_or_insert(e);
        event_loop.exit();
    }
}

impl ApplicationHandler<Signalled> for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if let Err(e) = self.open(event_loop) {
            self.fail(event_loop, e);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(viewer) = self.viewer.as_mut() else {
            return;
        };
        let result = match event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::Resized(_) => {
                viewer.resize = true;
                viewer.dirty = true;
                Ok(())
            }
            WindowEvent::RedrawRequested => viewer.draw(self.args).map(|done| {
                if done {
                    event_loop.exit()
                }
            }),
            WindowEvent::ModifiersChanged(m) => {
                viewer.modifiers = m.state();
                Ok(())
            }
            // A modifier or lock key alone is part of another key, not one.
            WindowEvent::KeyboardInput { event, .. }
                if event.state == ElementState::Pressed && !is_modifier(&event.logical_key) =>
            {
                let name = match &event.logical_key {
                    Key::Named(named) => format!("{named:?}"),
                    Key::Character(c) => c.to_string(),
                    _ => String::new(),
                };
                let quit = viewer.key(&name);
                if quit {
                    event_loop.exit();
                }
                Ok(()).and_then(|_| viewer.key_result.take().map_or(Ok(()), Err))
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let down = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => viewer.buttons.0 = down,
                    MouseButton::Right | MouseButton::Middle => viewer.buttons.1 = down,
                    _ => {}
                }
                Ok(())
            }
            WindowEvent::CursorMoved { position, .. } => {
                let now = (position.x, position.y);
                if let Some(before) = viewer.cursor {
                    let (dx, dy) = (now.0 - before.0, now.1 - before.1);
                    viewer.dirty |= viewer.buttons.0 || viewer.buttons.1;
                    if viewer.buttons.0 {
                        viewer.controls.orbit(dx, dy);
                    } else if viewer.buttons.1 {
                        // In frame pixels: fewer than the window's where
                        // the frame is scaled up to it (`render_size`).
                        let window = viewer.window.inner_size().height.max(1) as f64;
                        let k = viewer.controls.size.1 as f64 / window;
                        viewer.controls.drag_pan(dx * k, dy * k);
                    }
                }
                viewer.cursor = Some(now);
                Ok(())
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y as f64,
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
                viewer.controls.scroll(lines);
                viewer.dirty = true;
                Ok(())
            }
            _ => Ok(()),
        };
        if let Err(e) = result {
            self.fail(event_loop, e);
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        // A minimised (zero-sized) window waits for its Resized, even
        // while a series plays.
        let shown = |v: &&Viewer| {
            let size = v.window.inner_size();
            size.width > 0 && size.height > 0
        };
        if let Some(viewer) = self.viewer.as_ref().filter(shown).filter(|v| v.wants_frame(self.args)) {
            viewer.window.request_redraw();
        }
    }

    /// Ctrl-C or SIGTERM (`end_on_signals`): the session ends as Q ends it.
    fn user_event(&mut self, event_loop: &ActiveEventLoop, _: Signalled) {
        event_loop.exit();
    }
}

impl Viewer {
    /// Whether to draw now: after a change, while a series plays, and
    /// through `--frames` and `--keys`. An unchanged window is not redrawn
    /// (only when the window system asks, `RedrawRequested`).
    fn wants_frame(&self, args: &ViewArgs) -> bool {
        self.dirty || self.controls.playing || args.frames.is_some() || !self.pending_keys.is_empty()
    }

    /// Draws one frame; true when `--frames` are done.
    fn draw(&mut self, args: &ViewArgs) -> Result<bool> {
        let started = Instant::now();
        if self.resize {
            let size = self.window.inner_size();
            if size.width == 0 || size.height == 0 {
                // Minimised: nothing to draw until it is resized back.
                self.dirty = false;
                return Ok(false);
            }
            let extent = self.host.resize((size.width, size.height))?;
            self.controls.size = self.render_size((extent.width, extent.height));
            self.resize = false;
        }
        let last = args.frames.is_some_and(|n| self.drawn + 1 >= n);
        let shot = last && args.screenshot.is_some();
        let volume = &self.scene.volume;
        let desc = self.controls.desc(volume.dims, volume.spacing, self.filter)?;
        let lit = desc.lighting().is_some();
        if self.shown != self.controls.time {
            // A step that does not load (a file cut short) is named and
            // the shown one kept; play stops there.
            match self.take_step(self.controls.time) {
                Ok((volume, load_ms)) => {
                    self.load_ms = load_ms;
                    self.scene.set_volume(volume, lit)?;
                    self.shown = self.controls.time;
                }
                Err(e) => {
                    say_err!("note: time step {} not shown: {e}", self.controls.time);
                    self.controls.time = self.shown;
                    self.controls.playing = false;
                }
            }
        }
        // The next step loads while this one uploads, builds and renders.
        if self.controls.playing && self.prefetch.is_none() {
            let next = (self.shown + 1) % self.series.steps();
            let series = self.series.clone();
            let load = std::thread::spawn(move || {
                let t = Instant::now();
                let volume = series.load(next, None)?;
                Ok((volume, t.elapsed().as_secs_f64() * 1000.0))
            });
            self.prefetch = Some((next, load));
        }
        if lit {
            self.scene.ensure_gradient()?;
        }
        self.scene.prepare(&desc)?;
        let ctx = self.scene.context().clone();
        let scene = &mut self.scene;
        let presented = self.host.frame(&ctx, |cmd, canvas| {
            scene.record(cmd, canvas, &desc, shot || self.shots > 0)
        })?;
        self.resize |= presented.stale;
        if !presented.drawn {
            return Ok(false);
        }
        self.scene.finish()?;
        self.drawn += 1;
        // A frame presented to a swapchain gone stale is drawn again on the
        // new one, once: a surface that stays suboptimal must not spin.
        self.dirty = presented.stale && !self.stale_redraw;
        self.stale_redraw = self.dirty;
        // S presses this frame was read back for; keys pressed now ask of the next.
        let shots = std::mem::take(&mut self.shots);
        self.press_pending()?;
        let last = last || self.quit;
        if self.controls.playing {
            self.controls.step_time(1);
        }
        let now = Instant::now();
        self.frame_ms = now.duration_since(started).as_secs_f64() * 1000.0;
        if let Some(dt) = self
            .last
            .map(|l| now.duration_since(l).as_secs_f64())
            .filter(|dt| *dt > 0.0)
        {
            self.fps = match self.fps {
                0.0 => 1.0 / dt,
                fps => 0.9 * fps + 0.1 / dt,
            };
        }
        self.last = self.wants_frame(args).then_some(now);
        self.window.set_title(&self.title());
        if shot {
            if let Some(path) = &args.screenshot {
                self.write(path, FrameFormat::from_path(path)?)?;
            }
        }
        if shots > 0 {
            self.shots_written += 1;
            // Numbered: one press does not replace the last, nor the
            // file --screenshot names.
            let stem = match &args.screenshot {
                Some(p) => p.with_extension(""),
                None => PathBuf::from(format!("lacuna-view-{}", std::process::id())),
            };
            let named = |ext: &str| {
                let mut name = stem.clone().into_os_string();
                name.push(format!("-{}.{ext}", self.shots_written));
                PathBuf::from(name)
            };
            self.write(&named("exr"), FrameFormat::Exr)?;
            self.write(&named("png"), FrameFormat::Png)?;
        }
        Ok(last)
    }

    /// The frame's size for a window of `window` pixels: the window's, or
    /// where the device cannot render that many (its storage range), the
    /// largest of the same shape it can, which the present step scales up.
    fn render_size(&self, window: (u32, u32)) -> (u32, u32) {
        let info = self.scene.context().info();
        let size = fit(window, |(w, h)| {
            lacuna::render::RenderTarget::check_size(info, w, h).is_ok()
        });
        // Once per frame size, not at every event of a drag.
        if size != window && size != self.controls.size {
            say_err!(
                "note: the window's {}x{} pixels are more than {} renders: rendering {}x{}, scaled to the window",
                window.0,
                window.1,
                info.name,
                size.0,
                size.1
            );
        }
        size
    }

    /// Step `k`: the one loading on the host thread when it is `k` (a
    /// step that failed to load fails here), else loaded now.
    fn take_step(&mut self, k: u32) -> Result<LoadedStep> {
        if let Some((next, load)) = self.prefetch.take() {
            let loaded = load
                .join()
                .map_err(|_| Error::Unsupported(format!("loading step {next} panicked")))?;
            if next == k {
                return loaded;
            }
        }
        let t = Instant::now();
        let volume = self.series.load(k, None)?;
        Ok((volume, t.elapsed().as_secs_f64() * 1000.0))
    }

    fn write(&self, path: &Path, format: FrameFormat) -> Result<()> {
        let Some(mut frame): Option<Frame> = self.scene.frame()? else {
            return Ok(());
        };
        // A frame the device's loop cap cut short is not written, as `render` refuses it.
        self.scene.check_whole()?;
        let volume = &self.scene.volume;
        let desc = self.controls.desc(volume.dims, volume.spacing, self.filter)?;
        let time = (self.series.steps() > 1).then_some(self.shown);
        self.scene.describe(&mut frame, &desc, time)?;
        frame.write(path, format)?;
        say!("wrote {}", path.display());
        Ok(())
    }
}
