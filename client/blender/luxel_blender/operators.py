"""Operators: bake (modal, Esc cancels), cancel, apply finished results."""

import os
import tempfile
import time

import bpy
from bpy.props import BoolProperty, StringProperty

from . import apply as applier
from . import preferences
from . import session as sessions

_TIMER_S = 0.2  # how often the UI polls the bake; the bake itself does not wait for it


def config_from_context(context):
    """The session's settings: the add-on's preferences and scene.luxel."""
    prefs = preferences.get(context)
    s = context.scene.luxel
    work_dir = prefs.work_dir if prefs and prefs.work_dir else ""
    if not work_dir:
        work_dir = ("//luxel" if bpy.data.filepath
                    else os.path.join(tempfile.gettempdir(), "luxel_blender"))
    blend = os.path.splitext(os.path.basename(bpy.data.filepath))[0]
    return sessions.Config(
        luxel_path=prefs.luxel_path if prefs else "luxel",
        use_server=(prefs.mode == "SERVER") if prefs else True,
        server=prefs.server if prefs else "127.0.0.1:50051",
        token_file=prefs.token_file if prefs else "",
        work_dir=work_dir,
        scene_name=blend or context.scene.name,
        selection_only=s.selection_only, resolution=s.resolution, samples=s.samples,
        bounces=s.bounces, time_s=s.time_s, snapshot_interval_s=s.snapshot_interval_s,
        extra_args=s.extra_args, baked_only=s.baked_only)


def show_progress(context, session):
    """Status bar text, the window manager's progress cursor, redraws."""
    wm = context.window_manager
    if session.phase in sessions.FINAL:
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)
    else:
        wm.progress_update(int(1000 * session.progress.fraction))
        if context.workspace is not None:
            context.workspace.status_text_set(session.status_text())
    image = bpy.data.images.get(applier.LIGHTMAP_IMAGE)
    for window in wm.windows:
        for area in window.screen.areas:
            if area.type == "IMAGE_EDITOR" and image is not None and area.spaces.active.image is None:
                area.spaces.active.image = image  # an empty Image Editor shows the bake
            if area.type in ("VIEW_3D", "IMAGE_EDITOR", "PROPERTIES", "STATUSBAR"):
                area.tag_redraw()


def report_end(op, session):
    for w in session.warnings:
        op.report({"WARNING"}, w)
    if session.phase == sessions.DONE:
        op.report({"INFO"}, f"Luxel: {session.message}")
        return {"FINISHED"}
    if session.phase == sessions.CANCELLED:
        op.report({"WARNING"}, f"Luxel: {session.message}")
    else:
        op.report({"ERROR"}, f"Luxel: {session.error or session.message}")
    return {"CANCELLED"}


class LUXEL_OT_bake(bpy.types.Operator):
    """Export the scene, bake its lightmap with Luxel and apply it"""
    bl_idname = "luxel.bake"
    bl_label = "Bake Lightmap"

    wait: BoolProperty(
        name="Wait", default=False, options={"SKIP_SAVE", "HIDDEN"},
        description="Block until the bake ends (scripts and `blender -b`, where no modal "
                    "operator runs)")

    _timer = None
    _session = None

    @classmethod
    def poll(cls, context):
        return sessions.active() is None

    def _start(self, context):
        self._session = sessions.Session(config_from_context(context))
        try:
            self._session.start(context)
        except RuntimeError as e:
            self.report({"ERROR"}, f"Luxel: {e}")
            return False
        context.window_manager.progress_begin(0, 1000)
        return True

    def execute(self, context):
        if not self._start(context):
            return {"CANCELLED"}
        session = self._session
        if self.wait:
            while session.step():
                time.sleep(_TIMER_S)
            show_progress(context, session)
            return report_end(self, session)

        def tick():
            running = session.step()
            show_progress(bpy.context, session)
            if not running:
                print(f"Luxel: {session.error or session.message}")
            return _TIMER_S if running else None

        bpy.app.timers.register(tick, first_interval=_TIMER_S)
        return {"FINISHED"}

    def invoke(self, context, event):
        if self.wait:
            return self.execute(context)
        if not self._start(context):
            return {"CANCELLED"}
        self._timer = context.window_manager.event_timer_add(_TIMER_S, window=context.window)
        context.window_manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        session = self._session
        if event.type == "ESC" and event.value == "PRESS":
            session.cancel()
        if event.type != "TIMER" and event.type != "ESC":
            return {"PASS_THROUGH"}  # the UI stays usable while the bake runs
        running = session.step()
        show_progress(context, session)
        if running:
            return {"RUNNING_MODAL"}
        context.window_manager.event_timer_remove(self._timer)
        return report_end(self, session)


class LUXEL_OT_cancel(bpy.types.Operator):
    """Cancel the running Luxel bake (the daemon marks it CANCELLED)"""
    bl_idname = "luxel.cancel"
    bl_label = "Cancel Bake"

    @classmethod
    def poll(cls, context):
        return sessions.active() is not None

    def execute(self, context):
        sessions.active().cancel()
        self.report({"INFO"}, "Luxel: cancelling")
        return {"FINISHED"}


class LUXEL_OT_apply(bpy.types.Operator):
    """Apply a finished bake's folder (irradiance.exr, manifest.json and
    <scene>_lightmapped.glb) to the objects of the same names"""
    bl_idname = "luxel.apply_results"
    bl_label = "Apply Bake Results"

    directory: StringProperty(subtype="DIR_PATH")

    def execute(self, context):
        folder = bpy.path.abspath(self.directory)
        glbs = [f for f in sorted(os.listdir(folder)) if f.endswith("_lightmapped.glb")] \
            if os.path.isdir(folder) else []
        if not glbs or not os.path.isfile(os.path.join(folder, "irradiance.exr")):
            self.report({"ERROR"}, f"Luxel: {folder} holds no irradiance.exr and *_lightmapped.glb")
            return {"CANCELLED"}
        glb = os.path.join(folder, glbs[0])
        try:
            objects, warnings = applier.apply_results(folder, glb, glb, context.scene.luxel.baked_only)
        except Exception as e:
            self.report({"ERROR"}, f"Luxel: {e}")
            return {"CANCELLED"}
        for w in warnings:
            self.report({"WARNING"}, w)
        self.report({"INFO"}, f"Luxel: lightmap applied to {len(objects)} objects")
        return {"FINISHED"}

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}


class LUXEL_OT_restore(bpy.types.Operator):
    """Give the selected objects back the meshes they had before their first
    Luxel bake (the materials keep their Luxel nodes; set "Luxel Mix" to 0)"""
    bl_idname = "luxel.restore_meshes"
    bl_label = "Restore Original Meshes"

    def execute(self, context):
        n = sum(applier.restore_original(o) for o in context.selected_objects)
        self.report({"INFO"}, f"Luxel: {n} objects restored")
        return {"FINISHED"}


classes = (LUXEL_OT_bake, LUXEL_OT_cancel, LUXEL_OT_apply, LUXEL_OT_restore)
