"""raysplat as a Blender render engine: F12 exports the scene with Blender's glTF exporter,
runs the raysplat command on it, shows its progress, and loads its passes into the render
result. Esc stops the command (SIGINT); it writes nothing and the add-on removes its files.

Render Animation (Ctrl+F12): Blender asks for the frames one at a time. At the first, the scene
is exported once with its animation and ONE raysplat process renders the whole range (--frames
start-end --frame-step step), so that the photons are traced once where only the camera moves;
each later call waits for its frame's file and loads it. Esc stops the process."""

bl_info = {
    "name": "raysplat",
    "description": "Global illumination by photon ray splatting, with the raysplat command",
    "blender": (4, 2, 0),
    "version": (1, 0, 0),
    "category": "Render",
    "location": "Render Properties > Render Engine > raysplat",
}

import os
import shutil
import tempfile

import bpy

from . import export, runner

ENGINE = "RAYSPLAT"
PASSES = [  # (Blender pass, channels, type): the CLI's layers as --blender-layer names them
    ("Direct", "RGB", "COLOR"),
    ("Indirect", "RGB", "COLOR"),
    ("Caustic", "RGB", "COLOR"),
    ("Emission", "RGB", "COLOR"),
    ("Albedo", "RGB", "COLOR"),
    ("Normal", "XYZ", "VECTOR"),
]
last_error = None  # the last failure's message, as reported (for scripts and tests)
last_stopped = False  # whether Esc stopped the last render (for scripts and tests)


def preferences(context=None):
    return (context or bpy.context).preferences.addons[__package__].preferences


class RaysplatPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__
    binary: bpy.props.StringProperty(name="raysplat binary", subtype="FILE_PATH",
                                     description="The raysplat command (empty: the one on PATH)")
    keep_files: bpy.props.BoolProperty(name="Keep the exported files",
                                       description="Keep each render's .glb and .exr in a temporary folder and say where")

    def draw(self, context):
        self.layout.prop(self, "binary")
        self.layout.prop(self, "keep_files")


class RaysplatSettings(bpy.types.PropertyGroup):
    # 0 (or off) leaves a setting at the command's own default, which the panel shows.
    reference: bpy.props.BoolProperty(name="Reference path tracer", description="Render with raysplat's path tracer (--method path)")
    use_time_limit: bpy.props.BoolProperty(name="Time limit", description="Render passes until the time is up, instead of a number of passes")
    time_limit: bpy.props.FloatProperty(name="Seconds", default=10.0, min=0.1, description="--time-limit")
    passes: bpy.props.IntProperty(name="Passes", min=0, description="--passes (0: the command's default)")
    spp: bpy.props.IntProperty(name="Samples a pass", min=0, description="--spp (0: the command's default)")
    photons: bpy.props.IntProperty(name="Photons a pass", min=0, description="--photons (0: the command's default)")
    light_samples: bpy.props.IntProperty(name="Light samples", min=0, description="--light-samples (0: the command's default)")
    grid: bpy.props.IntProperty(name="Grid", min=0, max=4096, description="--grid, voxels along the longest axis (0: the command's default)")
    threads: bpy.props.IntProperty(name="Threads", min=0, description="--threads (0: every core)")
    seed: bpy.props.IntProperty(name="Seed", min=0, description="--seed")


def render_options(settings):
    """The command-line options for the panel's settings; unset ones are left to the command."""
    opts = ["--method", "path" if settings.reference else "splat"]
    if settings.use_time_limit:
        opts += ["--time-limit", f"{settings.time_limit:.9g}"]
    elif settings.passes:
        opts += ["--passes", str(settings.passes)]
    for flag, value in (("--spp", settings.spp), ("--photons", settings.photons), ("--light-samples", settings.light_samples),
                        ("--grid", settings.grid), ("--threads", settings.threads), ("--seed", settings.seed)):
        if value:
            opts += [flag, str(value)]
    return opts


class RaysplatRenderEngine(bpy.types.RenderEngine):
    bl_idname = ENGINE
    bl_label = "raysplat"
    bl_use_preview = False

    def update_render_passes(self, scene=None, renderlayer=None):
        self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", "COLOR")
        for name, channels, kind in PASSES:
            self.register_pass(scene, renderlayer, name, len(channels), channels, kind)

    def render(self, depsgraph):
        global last_error, last_stopped
        last_error, last_stopped = None, False
        scene = depsgraph.scene
        prefs = preferences()
        if self.is_animation:
            try:
                self._render_frame(scene, prefs)
            except runner.RaysplatError as e:
                end_animation()
                self._fail(e)
            return
        work = tempfile.mkdtemp(prefix="raysplat-")
        try:
            self._render(scene, prefs, work)
        except runner.RaysplatError as e:
            self._fail(e)
        finally:
            if prefs.keep_files and os.path.isdir(work):
                self.report({"INFO"}, f"raysplat: files kept in {work}")
            else:
                shutil.rmtree(work, ignore_errors=True)

    def _fail(self, e):
        global last_error
        last_error = str(e)
        self.report({"ERROR"}, f"raysplat: {e}")
        if hasattr(self, "error_set"):
            self.error_set(f"raysplat: {e}")

    def _command(self, scene, prefs, glb, exr, first_frame=None):
        """Exports the scene to `glb` and returns the command that renders it to `exr`; with
        `first_frame`, the animation too, and the frames from it to the scene's end."""
        animation = first_frame is not None
        binary = runner.find_binary(prefs.binary)
        if scene.camera is None:
            raise runner.RaysplatError("the scene has no active camera")
        width, height = export.resolution(scene)
        self.update_stats("", "raysplat: exporting glTF" + (" with the animation" if animation else ""))
        export.export_glb(bpy.context, glb, animation=animation)
        layer = scene.view_layers[0].name if len(scene.view_layers) == 1 else bpy.context.view_layer.name
        cmd = [binary, "render", glb, "-o", exr, "--width", str(width), "--height", str(height),
               "--camera", scene.camera.data.name, "--blender-layer", layer, "--progress", "json"]
        cmd += render_options(scene.raysplat) + export.world_options(scene, self.report)
        if animation:
            r = scene.render
            # The exporter times frame n at n / (fps × fps_base) (io_scene_gltf2 4.2): the same here.
            cmd += ["--frames", f"{first_frame}-{scene.frame_end}", "--frame-step", str(scene.frame_step),
                    "--fps", f"{r.fps * r.fps_base:.9g}"]
        with open(os.path.join(os.path.dirname(glb), "command.txt"), "w") as f:
            f.write("\n".join(cmd) + "\n")
        return cmd

    def _stop_asked(self):
        """Esc: Blender's test_break. (A test replaces this method: RNA's test_break itself
        cannot be overridden from Python, its functions come before a class's attributes.)"""
        return self.test_break()

    def _on_event(self, event):
        if event.get("event") == "progress":
            done, total = event.get("done", 0), event.get("total", 0)
            if total:
                self.update_progress(min(1.0, (done + event.get("inner_fraction", 0.0)) / total))
            self.update_stats("", runner.describe(event))
        elif event.get("event") == "warning":
            self.report({"WARNING"}, "raysplat: " + event.get("message", ""))

    def _load(self, scene, exr):
        width, height = export.resolution(scene)
        result = self.begin_result(0, 0, width, height)
        result.load_from_file(exr)
        self.end_result(result)

    def _render(self, scene, prefs, work):
        exr = os.path.join(work, "render.exr")
        cmd = self._command(scene, prefs, os.path.join(work, "scene.glb"), exr)
        global last_stopped
        if not runner.run(cmd, self._on_event, self._stop_asked):
            last_stopped = True
            return  # stopped: nothing was written
        self._load(scene, exr)

    def _render_frame(self, scene, prefs):
        """One frame of Render Animation: the range's process started at its first frame (or
        again when the range or the settings changed), then this frame's file awaited."""
        global animation_job, last_stopped
        frame = scene.frame_current
        key = (scene.name, scene.frame_start, scene.frame_end, scene.frame_step, export.resolution(scene),
               scene.camera and scene.camera.name, tuple(render_options(scene.raysplat)))
        job = animation_job
        if job is None or job.key != key or frame <= job.last:
            end_animation()
            work = tempfile.mkdtemp(prefix="raysplat-")
            job = animation_job = AnimationJob(key, work, prefs.keep_files)
            # From this frame on: Blender starts past the frames whose files exist when it may
            # not overwrite them, and a frame is the same image in any range.
            cmd = self._command(scene, prefs, os.path.join(work, "scene.glb"), os.path.join(work, "frame_######.exr"),
                                first_frame=frame)
            job.frames = runner.FrameRun(cmd, lambda f: os.path.join(work, f"frame_{f:06d}.exr"))
        exr = job.frames.wait_frame(frame, self._on_event, self._stop_asked)
        if exr is None:  # Esc: the process is stopped
            last_stopped = True
            end_animation()
            return
        job.last = frame
        self._load(scene, exr)
        if not job.keep:
            os.remove(exr)
        if frame + scene.frame_step > scene.frame_end:  # the last frame: the process ends
            job.frames.finish()
            end_animation()


class AnimationJob:
    """A Render Animation in progress, kept from frame to frame (Blender makes a new engine each frame)."""

    def __init__(self, key, work, keep):
        self.key, self.work, self.keep = key, work, keep
        self.frames = None  # runner.FrameRun
        self.last = -(1 << 62)  # the last frame handed to Blender


animation_job = None


def end_animation(*_args):
    """Stops the Render Animation's process, if any, and removes its folder (unless kept). Also a
    render_cancel / render_complete handler, so that a job Blender ends is not left running."""
    global animation_job
    job, animation_job = animation_job, None
    if job is None:
        return
    if job.frames is not None:
        job.frames.stop()
    if job.keep:
        print(f"raysplat: files kept in {job.work}")
    else:
        shutil.rmtree(job.work, ignore_errors=True)


class RAYSPLAT_OT_show_grid(bpy.types.Operator):
    """Voxelize the scene with raysplat and show its occlusion grid as a volume object"""
    bl_idname = "raysplat.show_grid"
    bl_label = "Show occlusion grid"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        scene = context.scene
        try:
            binary = runner.find_binary(preferences(context).binary)
            folder = bpy.path.abspath("//") if bpy.data.filepath else bpy.app.tempdir or tempfile.gettempdir()
            vdb = os.path.join(folder, f"{bpy.path.clean_name(scene.name)}_raysplat_grid.vdb")
            with tempfile.TemporaryDirectory(prefix="raysplat-") as work:
                glb = os.path.join(work, "scene.glb")
                export.export_glb(context, glb)
                cmd = [binary, "voxelize", glb, "-o", vdb, "--progress", "json"]
                if scene.raysplat.grid:
                    cmd += ["--grid", str(scene.raysplat.grid)]
                runner.run(cmd)
        except runner.RaysplatError as e:
            self.report({"ERROR"}, f"raysplat: {e}")
            return {"CANCELLED"}
        name = "raysplat occlusion grid"
        old = bpy.data.objects.get(name)
        if old is not None:
            bpy.data.objects.remove(old)
        volume = bpy.data.volumes.new(name)
        volume.filepath = vdb
        obj = bpy.data.objects.new(name, volume)  # the grid's transform already holds glTF's Y up → Z up
        scene.collection.objects.link(obj)
        self.report({"INFO"}, f"raysplat: occlusion grid {vdb}")
        return {"FINISHED"}


class RENDER_PT_raysplat(bpy.types.Panel):
    bl_label = "raysplat"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    COMPAT_ENGINES = {ENGINE}

    @classmethod
    def poll(cls, context):
        return context.engine == ENGINE

    def draw(self, context):
        s = context.scene.raysplat
        layout = self.layout
        layout.use_property_split = True
        try:
            d = runner.cli_defaults(runner.find_binary(preferences(context).binary))
        except (runner.RaysplatError, OSError, ValueError) as e:
            layout.label(text=str(e), icon="ERROR")
            d = None
        method = "path" if s.reference else "splat"

        def row(prop, default):
            layout.prop(s, prop)
            if d is not None and not getattr(s, prop):
                layout.label(text=f"0: the default, {default}")

        layout.prop(s, "reference")
        layout.prop(s, "use_time_limit")
        if s.use_time_limit:
            layout.prop(s, "time_limit")
        else:
            row("passes", d and d["passes"][method])
        row("spp", d and d["spp"][method])
        if not s.reference:
            row("photons", d and d["photons"])
        row("light_samples", d and d["light_samples"])
        row("grid", d and d["grid"])
        layout.prop(s, "threads")
        layout.prop(s, "seed")
        layout.operator(RAYSPLAT_OT_show_grid.bl_idname)


# Blender's own panels that make sense for any engine (resolution, output, colour management).
def _compatible_panels():
    for name in dir(bpy.types):
        panel = getattr(bpy.types, name)
        if hasattr(panel, "COMPAT_ENGINES") and "BLENDER_EEVEE_NEXT" in panel.COMPAT_ENGINES:
            yield panel


CLASSES = (RaysplatPreferences, RaysplatSettings, RaysplatRenderEngine, RAYSPLAT_OT_show_grid, RENDER_PT_raysplat)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    for handlers in (bpy.app.handlers.render_cancel, bpy.app.handlers.render_complete):
        handlers.append(end_animation)
    bpy.types.Scene.raysplat = bpy.props.PointerProperty(type=RaysplatSettings)
    for panel in _compatible_panels():
        panel.COMPAT_ENGINES.add(ENGINE)


def unregister():
    end_animation()
    for handlers in (bpy.app.handlers.render_cancel, bpy.app.handlers.render_complete):
        if end_animation in handlers:
            handlers.remove(end_animation)
    for panel in _compatible_panels():
        panel.COMPAT_ENGINES.discard(ENGINE)
    del bpy.types.Scene.raysplat
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
