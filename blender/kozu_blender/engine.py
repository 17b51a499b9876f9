"""kozu as a Blender render engine (bl_idname "KOZU"): F12 and bpy.ops.render.render export the scene to a
temporary folder, run the kozu binary on it, show its progress in the status bar, cancel it with Esc (SIGINT: kozu
writes what it has rendered), and load the EXR, with AOVs as render passes, into the Render Result.
"""
import os
import shutil
import signal
import subprocess
import tempfile
import threading
import traceback

import bpy
import numpy as np

from . import export, mapping

# Render passes kozu writes as AOVs: Blender pass name -> (view layer flag, kozu AOV, EXR channels, Blender channel ids)
PASSES = {
    "Depth": ("use_pass_z", "depth", ["Z"], "Z"),
    "Normal": ("use_pass_normal", "normal", ["N.X", "N.Y", "N.Z"], "XYZ"),
    "DiffCol": ("use_pass_diffuse_color", "albedo", ["albedo.R", "albedo.G", "albedo.B"], "RGB"),
}


def find_kozu(context=None):
    """The kozu binary: the add-on's preferences, else $KOZU, else PATH; None when none is found."""
    prefs = None
    try:
        prefs = (context or bpy.context).preferences.addons[__package__].preferences
    except (KeyError, AttributeError):
        pass
    for candidate in ((prefs.kozu_path if prefs else ""), os.environ.get("KOZU", "")):
        if candidate:
            path = bpy.path.abspath(candidate)
            if os.path.isfile(path) and os.access(path, os.X_OK):
                return path
    return shutil.which("kozu")


def cancel_requested(engine):
    """Whether the user pressed Esc. A module function, so that tests can stand in for the key (bpy resolves
    engine.test_break to Blender's own method before any Python override)."""
    return engine.test_break()


class _StderrReader(threading.Thread):
    """Reads kozu's stderr: its progress bar redraws with carriage returns, messages end with newlines."""

    def __init__(self, stream):
        super().__init__(daemon=True)
        self.stream = stream
        self.lines = []
        self.progress = 0.0
        self.status = ""
        self.lock = threading.Lock()

    def run(self):
        buf = b""
        while True:
            chunk = self.stream.read1(4096) if hasattr(self.stream, "read1") else self.stream.read(1)
            if not chunk:
                break
            buf += chunk
            while True:
                cut = min([i for i in (buf.find(b"\r"), buf.find(b"\n")) if i >= 0], default=-1)
                if cut < 0:
                    break
                line, buf = buf[:cut].decode("utf-8", "replace").strip(), buf[cut + 1:]
                if line:
                    self._take(line)
        if buf.strip():
            self._take(buf.decode("utf-8", "replace").strip())

    def _take(self, line):
        with self.lock:
            if line.startswith("[") and "%" in line:
                try:
                    self.progress = float(line.split("]")[1].split("%")[0]) / 100.0
                except (IndexError, ValueError):
                    pass
                self.status = " ".join(line.split("]", 1)[1].split())
            else:
                self.lines.append(line)


def load_exr_rgba(path, width, height):
    """An EXR's RGBA (bottom row first, as Blender's passes store it), read through Blender's image loader."""
    img = bpy.data.images.load(path, check_existing=False)
    try:
        if tuple(img.size) != (width, height):
            raise RuntimeError(f"kozu wrote a {img.size[0]} x {img.size[1]} image, expected {width} x {height}")
        pixels = np.empty(width * height * 4, dtype=np.float32)
        img.pixels.foreach_get(pixels)
        return pixels.reshape(-1, 4)
    finally:
        bpy.data.images.remove(img)


class KozuRenderEngine(bpy.types.RenderEngine):
    bl_idname = "KOZU"
    bl_label = "kozu"
    bl_use_preview = False
    bl_use_postprocess = True
    bl_use_shading_nodes_custom = False  # materials are Cycles' node trees, which the exporter reads

    def update_render_passes(self, scene=None, renderlayer=None):
        self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", "COLOR")
        for name, (flag, _, channels, ids) in PASSES.items():
            if getattr(renderlayer, flag, False):
                self.register_pass(scene, renderlayer, name, len(channels), ids,
                                   "VALUE" if len(channels) == 1 else ("VECTOR" if name == "Normal" else "COLOR"))

    def render(self, depsgraph):
        scene = depsgraph.scene
        r = scene.render
        width, height = mapping.render_resolution(r.resolution_x, r.resolution_y, r.resolution_percentage)
        kozu = find_kozu()
        if kozu is None:
            self.report({"ERROR"}, "kozu: the kozu binary was not found (set it in the add-on's preferences, or "
                                   "the KOZU environment variable, or put it on PATH)")
            return
        layer = depsgraph.view_layer
        wanted = {name: spec for name, spec in PASSES.items() if getattr(layer, spec[0], False)}
        oiiotool = shutil.which("oiiotool")
        if wanted and oiiotool is None:
            self.report({"WARNING"}, "kozu: render passes need OpenImageIO's oiiotool on PATH: Combined only")
            wanted = {}
        with tempfile.TemporaryDirectory(prefix="kozu_blender_") as tmp:
            scene_file = os.path.join(tmp, "scene.json")
            self.update_stats("", "kozu: exporting the scene")
            try:
                exporter = export.export_scene(depsgraph, scene_file)
            except export.ExportError as e:
                self.report({"ERROR"}, f"kozu: {e}")
                return
            except Exception as e:  # a bug or an unforeseen scene: said in Blender's report, not a lost render
                traceback.print_exc()
                self.report({"ERROR"}, f"kozu: the export failed: {type(e).__name__}: {e}")
                return
            if r.use_border:
                exporter.report.add("render", "border render: kozu renders the whole frame")
            if exporter.report.lines:
                self.report({"WARNING"}, f"kozu: {len(exporter.report.lines)} things not mapped exactly:\n"
                            + "\n".join(exporter.report.lines))
            out = os.path.join(tmp, "render.exr")
            cmd = [kozu, "render", scene_file, "-o", out, "--resolution", f"{width}x{height}"]
            cmd += [a for a in exporter.args if a != "--alpha"] + ["--alpha"]
            if wanted:
                cmd += ["--aov", ",".join(spec[1] for spec in wanted.values())]
            if r.threads_mode == "FIXED":
                cmd += ["--threads", str(r.threads)]
            if not self._run(cmd, out):
                return
            result = self.begin_result(0, 0, width, height)
            try:
                passes = result.layers[0].passes
                rgba = load_exr_rgba(out if not wanted else self._split(oiiotool, out, tmp, "R,G,B,A", "beauty"),
                                     width, height)
                if not r.film_transparent:
                    rgba[:, 3] = 1.0
                passes["Combined"].rect = rgba
                for name, (_, _, channels, _) in wanted.items():
                    p = passes.get(name)
                    if p is None:
                        continue
                    path = self._split(oiiotool, out, tmp, ",".join(channels + ["A"] * (3 - len(channels)) + ["A"]),
                                       name)
                    data = load_exr_rgba(path, width, height)[:, :len(channels)]
                    if name == "Normal":
                        data = np.stack([data[:, 0], -data[:, 2], data[:, 1]], axis=1)  # kozu's y-up to z-up
                    p.rect = np.ascontiguousarray(data)
            except (RuntimeError, OSError, subprocess.CalledProcessError) as e:
                self.report({"ERROR"}, f"kozu: reading its image failed: {e}")
            finally:
                self.end_result(result)

    def _split(self, oiiotool, exr, tmp, channels, name):
        """One EXR of four channels out of kozu's (oiiotool --ch), for Blender's single-layer image loader."""
        path = os.path.join(tmp, name + ".exr")
        subprocess.run([oiiotool, exr, "--ch", channels, "--chnames", "R,G,B,A", "-o", path], check=True,
                       capture_output=True)
        return path

    def _run(self, cmd, out):
        """Runs kozu; progress to the status bar, Esc sends SIGINT. True when it wrote an image."""
        self.update_stats("", "kozu: starting")
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        reader = _StderrReader(proc.stderr)
        reader.start()
        cancelled = False
        while proc.poll() is None:
            try:
                proc.wait(timeout=0.1)
            except subprocess.TimeoutExpired:
                pass
            with reader.lock:
                progress, status = reader.progress, reader.status
            self.update_progress(progress)
            if status:
                self.update_stats("", f"kozu: {status}")
            if not cancelled and cancel_requested(self):
                cancelled = True
                proc.send_signal(signal.SIGINT)  # kozu finishes the pass and writes what it has
        reader.join(timeout=5)
        if cancelled and proc.returncode == 128 + signal.SIGINT and os.path.isfile(out):
            # kozu stopped at Esc and wrote the samples it had: show them.
            self.report({"INFO"}, "kozu: cancelled; the image has the samples rendered so far")
            return True
        if proc.returncode != 0:
            message = "\n".join(reader.lines[-10:]) or f"exit status {proc.returncode}"
            self.report({"ERROR"}, f"kozu failed: {message}")
            return False
        return True


def _compatible_panels():
    """Cycles' material, light, world and camera panels, which the exporter reads, shown for kozu too."""
    for name in dir(bpy.types):
        panel = getattr(bpy.types, name, None)
        engines = getattr(panel, "COMPAT_ENGINES", None)
        if isinstance(engines, set) and "CYCLES" in engines and (
                name.startswith(("CYCLES_MATERIAL", "CYCLES_LIGHT", "CYCLES_WORLD", "CYCLES_CAMERA",
                                 "DATA_PT", "MATERIAL_PT", "WORLD_PT", "RENDER_PT_format", "RENDER_PT_dimensions",
                                 "EEVEE_MATERIAL_PT", "NODE_DATA_PT"))):
            yield panel


def register():
    bpy.utils.register_class(KozuRenderEngine)
    for panel in _compatible_panels():
        panel.COMPAT_ENGINES.add("KOZU")


def unregister():
    for panel in _compatible_panels():
        panel.COMPAT_ENGINES.discard("KOZU")
    bpy.utils.unregister_class(KozuRenderEngine)
