"""One bake from Blender: export, check the daemon, bake, stream snapshots,
apply. A state machine advanced by step(), which a modal operator or a
bpy.app.timers callback calls a few times a second on the main thread; the
`luxel` process does the waiting, so Blender never blocks on the network."""

import atexit
import dataclasses
import os
import re
import shlex
import shutil
import time

import bpy

from . import apply as applier
from . import cli

# Phases of a session, in order; DONE, FAILED and CANCELLED are final.
EXPORT, CONNECT, BAKE, APPLY, DONE, FAILED, CANCELLED = (
    "EXPORT", "CONNECT", "BAKE", "APPLY", "DONE", "FAILED", "CANCELLED")
FINAL = {DONE, FAILED, CANCELLED}
HEALTH_TIMEOUT_S = 5.0   # `luxel health --timeout`: the daemon answers in milliseconds
CANCEL_GRACE_S = 30.0    # after a cancel, how long the bake may take to say it ended

_active = None  # the running session (one at a time), for the cancel operator and the UI


def active():
    return _active if _active is not None and _active.phase not in FINAL else None


@atexit.register
def _stop_processes():
    """Blender quitting mid-bake: no `luxel` outlives it. An in-process bake
    stops; a bake on luxeld goes on there (only its watcher stops) and can
    be fetched with `luxel fetch`."""
    if _active is not None:
        for proc in (_active._process, _active._cancel_process):
            if proc is not None:
                proc.terminate()


@dataclasses.dataclass
class Config:
    """Everything a session needs, copied from preferences and scene settings
    when it starts, so editing them mid-bake changes nothing."""
    luxel_path: str
    use_server: bool = True
    server: str = "127.0.0.1:50051"
    token_file: str = ""
    work_dir: str = ""
    scene_name: str = "scene"
    selection_only: bool = False
    resolution: int = 512
    samples: int = 256
    bounces: int = 4
    time_s: float = 0.0
    snapshot_interval_s: float = 1.0
    extra_args: str = ""
    baked_only: bool = True


@dataclasses.dataclass
class Progress:
    state: str = ""
    fraction: float = 0.0
    eta_s: float = -1.0
    mean_spp: float = 0.0
    error: float = 0.0
    elapsed_s: float = 0.0


def format_eta(seconds):
    if seconds is None or seconds < 0:
        return "--"
    seconds = int(round(seconds))
    return f"{seconds // 60}m{seconds % 60:02d}s" if seconds >= 60 else f"{seconds}s"


# `luxel bake --local` has no JSON mode; its progress lines (not a terminal):
# "[####....]  42.0%  spp 12.0 (min 8)  error 0.0837  3s elapsed  ETA 5s"
_LOCAL_PROGRESS = re.compile(r"\]\s*([\d.]+)%\s+spp ([\d.]+).*?error ([\d.eE+-]+).*?ETA (\S+)")


def _remove(path):
    if path:
        try:
            os.remove(path)
        except OSError:
            pass


def _parse_duration(text):
    if text == "--":
        return -1.0
    total, ok = 0.0, False
    for value, unit in re.findall(r"(\d+)([hms])", text):
        total += int(value) * {"h": 3600, "m": 60, "s": 1}[unit]
        ok = True
    return total if ok else -1.0


class Session:
    def __init__(self, config):
        self.config = config
        self.phase = EXPORT
        self.progress = Progress()
        self.message = ""          # the latest human-readable status
        self.error = ""            # set when the session FAILED
        self.bake_id = ""
        self.final_state = ""      # the daemon's word: SUCCEEDED, CANCELLED, FAILED
        self.snapshots = 0         # snapshots loaded into the lightmap image
        self.applied = []          # names of the objects that got the lightmap
        self.warnings = []
        self._process = None
        self._cancel_process = None
        self._cancel_requested = 0.0
        self._uploaded = False
        self._started = time.monotonic()
        self._pending_snapshot = None
        self._shown_snapshot = None
        root = bpy.path.abspath(config.work_dir) if config.work_dir else ""
        self.dir = os.path.join(root, bpy.path.clean_name(config.scene_name))
        self.scene_file = os.path.join(self.dir, bpy.path.clean_name(config.scene_name) + ".glb")
        self.results_dir = os.path.join(self.dir, "results")
        self.snapshots_dir = os.path.join(self.dir, "snapshots")

    # ------------------------------------------------------------ start

    def start(self, context):
        """Exports and launches the first process; raises RuntimeError with a
        message for the user when it cannot start."""
        global _active
        if active() is not None:
            raise RuntimeError("a Luxel bake is already running (cancel it first)")
        luxel = bpy.path.abspath(self.config.luxel_path)
        if not luxel or not os.path.isfile(luxel) or not os.access(luxel, os.X_OK):
            raise RuntimeError(f"the luxel binary '{self.config.luxel_path}' is not an executable "
                               "file (set it in the add-on's preferences)")
        if self.config.selection_only and not any(o.type == "MESH" for o in context.selected_objects):
            raise RuntimeError("\"Selected objects only\" is on and no mesh object is selected")
        self._luxel = luxel
        self._env = cli.token_env(self.config.token_file) if self.config.use_server else None
        for d in (self.results_dir, self.snapshots_dir):
            shutil.rmtree(d, ignore_errors=True)
        os.makedirs(self.snapshots_dir, exist_ok=True)
        self._export(context)
        _active = self
        if self.config.use_server:
            self.phase = CONNECT
            self.message = f"connecting to luxeld at {self.config.server}"
            self._process = cli.Process([luxel, "health", "--server", self.config.server,
                                         "--timeout", HEALTH_TIMEOUT_S], env=self._env)
        else:
            self._launch_bake()

    def _export(self, context):
        self.message = "exporting glTF"
        with applier.original_surfaces():
            result = self._export_gltf()
        if "FINISHED" not in result or not os.path.isfile(self.scene_file):
            raise RuntimeError(f"the glTF export to {self.scene_file} failed")

    def _export_gltf(self):
        return bpy.ops.export_scene.gltf(
            filepath=self.scene_file, export_format="GLB",
            use_selection=self.config.selection_only, use_visible=True,
            # The mesh data as it is: the baked geometry replaces it later,
            # under the object's modifiers, which would otherwise apply twice.
            export_apply=False,
            export_cameras=False, export_lights=True,
            # Blender's watts to glTF's radiometric units as Luxel reads
            # them (light intensities 1:1): W/(4 pi sr) for point lights.
            export_import_convert_lighting_mode="COMPAT",
            export_animations=False, export_skins=False, export_morph=False)

    def _launch_bake(self):
        c = self.config
        args = [self._luxel, "bake", self.scene_file, "--out", self.results_dir,
                "--resolution", c.resolution, "--samples", c.samples, "--bounces", c.bounces]
        if c.time_s > 0:
            args += ["--time", c.time_s]
        if c.use_server:
            args += ["--server", c.server, "--json", "--snapshots", self.snapshots_dir,
                     # float snapshots: the same irradiance the final map has,
                     # so the materials can show them as they come
                     "--snapshot-format", "exr", "--snapshot-interval", c.snapshot_interval_s,
                     # previews through the bake's denoiser (OIDN by default),
                     # so the first snapshot already looks like the result
                     "--denoise-snapshots",
                     "--progress-interval", min(1.0, c.snapshot_interval_s)]
        else:
            args += ["--local"]
        args += shlex.split(c.extra_args)
        self.phase = BAKE
        self.message = "uploading" if c.use_server else "baking in-process"
        self._process = cli.Process(args, env=self._env)

    # ------------------------------------------------------------ step

    def step(self):
        """Advances the session; True while it is not finished."""
        try:
            if self.phase == CONNECT:
                self._step_connect()
            elif self.phase == BAKE:
                self._step_bake()
        except Exception as e:  # a session must end, never leave a process behind
            self._fail(f"{type(e).__name__}: {e}")
        return self.phase not in FINAL

    def _step_connect(self):
        rc = self._process.returncode
        if rc is None:
            if time.monotonic() - self._started > HEALTH_TIMEOUT_S + 10:
                self._process.terminate()
                self._fail(f"luxeld at {self.config.server} did not answer within "
                           f"{HEALTH_TIMEOUT_S:.0f} s")
            return
        if self._cancel_requested:
            self._finish(CANCELLED, "cancelled before the upload")
        elif rc != cli.EXIT_OK:
            self._fail(f"cannot reach luxeld at {self.config.server}: {self._process.error_line()}")
        else:
            self._launch_bake()

    def _step_bake(self):
        for line in self._process.poll():
            self._take_line(line)
        if self._pending_snapshot:
            applier.lightmap_image(self._pending_snapshot)
            _remove(self._shown_snapshot)
            self._shown_snapshot, self._pending_snapshot = self._pending_snapshot, None
            self.snapshots += 1
        if self._cancel_process is None and self._cancel_requested and self.bake_id:
            self._send_cancel()
        if self._cancel_requested and time.monotonic() - self._cancel_requested > CANCEL_GRACE_S:
            self._process.terminate()
        rc = self._process.returncode
        if rc is None:
            return
        for line in self._process.poll():  # lines written just before it exited
            self._take_line(line)
        if rc == cli.EXIT_OK:
            self._apply()
        elif self.final_state in ("CANCELLED", "FAILED") or self._cancel_requested:
            state = CANCELLED if (self.final_state == "CANCELLED" or self._cancel_requested) else FAILED
            why = self._process.error_line()
            self._finish(state, f"bake {self.bake_id or '(not submitted)'} ended "
                                f"{self.final_state or 'CANCELLED'}" + ("" if state == CANCELLED else f": {why}"))
            if state == FAILED:
                self.error = self.message
        else:
            where = f" (luxeld at {self.config.server})" if self.config.use_server else ""
            self._fail(f"luxel bake failed{where}: {self._process.error_line()}")

    def _take_line(self, line):
        kind = line.get("type")
        if kind == "scene":
            self._uploaded = True
            self.message = "scene on the daemon"
        elif kind == "bake":
            self.bake_id = line["bake"]["bake_id"]
            self.message = f"bake {self.bake_id} queued"
        elif kind in ("event", "result"):
            info = line.get("info") or line.get("bake") or {}
            self._take_info(info)
            if line.get("snapshot_file"):
                # Only the newest is shown; the others are deleted, as every
                # shown one is once the next replaces it: a bake of an hour
                # at one float snapshot a second would fill gigabytes.
                _remove(self._pending_snapshot)
                self._pending_snapshot = line["snapshot_file"]
        elif kind == "artifact":
            self.message = f"downloaded {line.get('name')}"
        elif kind == "text":
            m = _LOCAL_PROGRESS.search(line["text"])
            if m:
                p = self.progress
                p.fraction = float(m.group(1)) / 100
                p.mean_spp, p.error = float(m.group(2)), float(m.group(3))
                p.eta_s = _parse_duration(m.group(4))
                p.state = "RUNNING"

    def _take_info(self, info):
        state = str(info.get("state", "")).replace("BAKE_STATE_", "")
        p = info.get("progress") or {}
        self.progress = Progress(state=state, fraction=float(p.get("fraction", 0.0)),
                                 eta_s=float(p.get("eta_s", -1.0)), mean_spp=float(p.get("mean_spp", 0.0)),
                                 error=float(p.get("error", 0.0)), elapsed_s=float(p.get("elapsed_s", 0.0)))
        if state in ("SUCCEEDED", "FAILED", "CANCELLED"):
            self.final_state = state
            if info.get("error_message"):
                self.error = info["error_message"]

    def _apply(self):
        self.phase = APPLY
        self.message = "applying the lightmap"
        glb = os.path.join(self.results_dir,
                           os.path.splitext(os.path.basename(self.scene_file))[0] + "_lightmapped.glb")
        # No write-back: Luxel baked the scene's own TEXCOORD_1 (on a
        # re-bake, the LuxelLightmap layer the first bake added).
        glb = glb if os.path.isfile(glb) else None
        objects, self.warnings = applier.apply_results(self.results_dir, glb, self.scene_file,
                                                       self.config.baked_only)
        self.applied = [o.name for o in objects]
        _remove(self._shown_snapshot)  # the image now reads irradiance.exr
        self._finish(DONE, f"lightmap applied to {len(objects)} objects")

    # ------------------------------------------------------------ cancel

    def cancel(self):
        """Asks the bake to stop; the session ends when luxel says it has."""
        if self.phase in FINAL or self._cancel_requested:
            return
        self._cancel_requested = time.monotonic()
        self.message = "cancelling"
        if self.phase == CONNECT:
            self._process.terminate()
        elif self.phase == BAKE:
            if not self.config.use_server:
                self._process.terminate()  # in-process bake: stopping the process is the cancel
            elif self.bake_id:
                self._send_cancel()
            elif not self._uploaded:
                self._process.terminate()  # still uploading: nothing submitted yet
            # else: submitted, the id comes with the next line; step() cancels it then

    def _send_cancel(self):
        self._cancel_process = cli.Process([self._luxel, "cancel", self.bake_id,
                                            "--server", self.config.server], env=self._env)

    # ------------------------------------------------------------ end

    def _fail(self, message):
        self.error = message
        self._finish(FAILED, message)

    def _finish(self, phase, message):
        global _active
        if self._process is not None and self._process.returncode is None:
            self._process.terminate()
            self._process.wait(5.0)
        if self._cancel_process is not None:
            self._cancel_process.wait(5.0)  # `luxel cancel` returns at once
        self.phase = phase
        self.message = message
        if _active is self:
            _active = None

    def status_text(self):
        p = self.progress
        if self.phase == BAKE and p.state == "RUNNING":
            return (f"Luxel: {100 * p.fraction:5.1f}%  spp {p.mean_spp:.1f}  error {p.error:.4f}  "
                    f"ETA {format_eta(p.eta_s)}  (Esc to cancel)")
        return f"Luxel: {self.message}"
