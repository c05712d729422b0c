//! `lucent view`: the interactive viewer (see [`crate::viewer`] for its parts).

use crate::cli::ViewArgs;
use crate::viewer::app::{App, Options, WorkerWake};
use crate::viewer::scene_file;
use crate::viewer::script::{self, Automation};
use crate::viewer::worker::MeshOrigin;
use anyhow::Context as _;
use lucent::scene::{Overrides, Scene};
use winit::event_loop::EventLoop;

/// Opens the viewer and runs until the window closes (or a scripted run finishes).
pub fn run(args: &ViewArgs) -> anyhow::Result<()> {
    let options = options(args)?;
    let event_loop = EventLoop::<WorkerWake>::with_user_event()
        .build()
        .context("opening a window needs a display (X11 or Wayland); headless, run it under `xvfb-run -a`")?;
    let mut app = App::new(options, event_loop.create_proxy());
    event_loop.run_app(&mut app).context("the event loop failed")?;
    match app.error.take() {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// Checks the arguments and builds the start-up options (before any window opens, so bad input
/// fails fast with a clear message).
fn options(args: &ViewArgs) -> anyhow::Result<Options> {
    if let Some(path) = &args.mesh
        && !path.is_file()
    {
        anyhow::bail!("--mesh {}: no such file", path.display());
    }
    if args.width < 200 || args.height < 150 {
        anyhow::bail!("--width/--height must be at least 200x150, got {}x{}", args.width, args.height);
    }
    // The same resolution as `lucent render`: flags over the scene file over the defaults.
    let overrides = Overrides {
        scene: args.scene.clone(),
        mesh: args.mesh.clone(),
        material: args.material.clone(),
        scale: args.scale,
        ..Overrides::default()
    };
    let scene = Scene::resolve(&overrides)?;
    let start = scene_file::start(&scene)?;
    // A scene file's `[camera]` as it is; without one, the viewer's home view.
    let camera = args.scene.is_some().then_some(start.camera);
    let entry = start.texture.as_ref().map(|t| t.entry_factors());
    let (mesh, mut state) = (MeshOrigin::Loaded(Box::new(start.mesh), entry), start.state);
    state.save = scene_file::save_target(args.scene.as_deref(), args.mesh.as_deref());
    state.save.refine = scene.refine_levels;
    let actions = match &args.script {
        Some(s) => script::parse(s)?,
        None => Vec::new(),
    };
    let scripted = args.frames.is_some() || args.script.is_some() || args.screenshot.is_some();
    let automation =
        scripted.then(|| Automation::new(args.frames.unwrap_or(10), actions, args.screenshot.clone()));
    Ok(Options { mesh, texture: start.texture, state, camera, automation, size: (args.width, args.height) })
}
