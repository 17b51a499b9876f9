"""Renders from Python (kozu.render, kozu.load, kozu.Scene) against the command line's.

The module's promise is that a render from Python is the render `kozu render` writes: the same float pixels,
bit for bit, for the same scene and settings, whether the scene comes as a path, a dict or a kozu.Scene, and with
AOVs and the denoiser. Also: errors name the file and the JSON path, the GIL is released while rendering, Ctrl-C
stops a render, progress is reported, and an edited scene renders again without reading its unchanged files.

Run by ctest (test_python_render) with PYTHONPATH=build/python and KOZU=the kozu command just built.
"""
import json
import os
import shutil
import signal
import subprocess
import tempfile
import threading
import time
import unittest

import numpy as np

import kozu

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.environ.get("KOZU_SOURCE_DIR", os.path.join(HERE, "..", ".."))
SCENES = os.path.join(SOURCE, "scenes")
KOZU = os.environ.get("KOZU", os.path.join(SOURCE, "build", "kozu"))


def scene_path(name):
    return os.path.join(SCENES, name + ".json")


class CommandLine:
    """`kozu render` into a temporary folder, its EXR read back with the module's reader (io/image_io.h)."""

    def __init__(self):
        self.dir = tempfile.mkdtemp(prefix="kozu-py-")

    def close(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def render(self, scene, *flags):
        out = os.path.join(self.dir, "cli.exr")
        subprocess.run([KOZU, "render", scene, "-q", "-o", out, *flags], check=True)
        return out


class RenderEqualsCommandLine(unittest.TestCase):
    """Bit-identical pixels: path, dict and kozu.Scene against the command's EXR."""

    @classmethod
    def setUpClass(cls):
        cls.cli = CommandLine()

    @classmethod
    def tearDownClass(cls):
        cls.cli.close()

    def check_scene(self, name, spp=4, res=(48, 40), seed=7):
        exr = self.cli.render(scene_path(name), "--spp", str(spp), "--resolution", f"{res[0]}x{res[1]}",
                              "--seed", str(seed))
        want = kozu.read_image(exr)
        self.assertEqual(want.shape, (res[1], res[0], 3))
        settings = dict(spp=spp, resolution=res, seed=seed)
        got = kozu.render(scene_path(name), **settings)
        self.assertEqual(got.dtype, np.float32)
        self.assertTrue(np.array_equal(got, want), f"{name}: path render differs from the CLI's")
        with open(scene_path(name)) as f:
            as_dict = json.load(f)
        got = kozu.render(as_dict, base_dir=SCENES, **settings)
        self.assertTrue(np.array_equal(got, want), f"{name}: dict render differs from the CLI's")
        scene = kozu.load(scene_path(name))
        got = kozu.render(scene, **settings)
        self.assertTrue(np.array_equal(got, want), f"{name}: kozu.Scene render differs from the CLI's")
        # A round trip through to_dict is the same scene.
        self.assertEqual(scene.to_dict(), as_dict)
        again = kozu.Scene(scene.to_dict(), base_dir=scene.base_dir)
        self.assertTrue(np.array_equal(kozu.render(again, **settings), want))
        # Different settings give a different image (the comparison can fail).
        self.assertFalse(np.array_equal(kozu.render(scene, spp=spp, resolution=res, seed=seed + 1), want))

    def test_cornell(self):
        self.check_scene("cornell")

    def test_subsurface_meshes(self):
        self.check_scene("subsurface", spp=2)

    def test_textured_polygon_light(self):
        self.check_scene("stained_glass", spp=2)

    def test_demo(self):
        exr = self.cli.render("--demo", "--spp", "2", "--resolution", "64x36")
        got = kozu.render(kozu.demo(), spp=2, resolution=(64, 36))
        self.assertTrue(np.array_equal(got, kozu.read_image(exr)))

    def test_aovs_and_denoiser(self):
        exr = self.cli.render(scene_path("cornell"), "--spp", "4", "--resolution", "40x40", "--aov",
                              "albedo,normal,depth", "--denoise")
        want, names = kozu.read_image(exr, names=True)
        denoised = kozu.read_image(exr.replace(".exr", ".denoised.exr"))[..., :3]  # its AOV channels follow
        got = kozu.render(scene_path("cornell"), spp=4, resolution=(40, 40), aovs=["albedo", "normal", "depth"],
                          denoise=True)
        self.assertEqual(sorted(got), ["albedo", "denoised", "depth", "normal", "rgb"])
        channels = {"rgb": ["R", "G", "B"], "albedo": ["albedo.R", "albedo.G", "albedo.B"],
                    "normal": ["N.X", "N.Y", "N.Z"], "depth": ["Z"]}
        for key, chans in channels.items():
            expected = want[..., [names.index(c) for c in chans]]
            self.assertEqual(got[key].shape, expected.shape, key)
            self.assertTrue(np.array_equal(got[key], expected), key)
        self.assertTrue(np.array_equal(got["denoised"], denoised))
        self.assertFalse(np.array_equal(got["denoised"], got["rgb"]))
        # denoise without AOVs returns the denoised image alone.
        only = kozu.render(scene_path("cornell"), spp=4, resolution=(40, 40), denoise=True)
        self.assertTrue(np.array_equal(only, denoised))
        # The other filters: the same pixels as the command's --denoiser, and other pixels than the default's.
        for name in ("regression", "unet"):
            exr = self.cli.render(scene_path("cornell"), "--spp", "4", "--resolution", "40x40", "--denoise-only",
                                  "--denoiser", name)
            got = kozu.render(scene_path("cornell"), spp=4, resolution=(40, 40), denoise=True, denoiser=name)
            self.assertTrue(np.array_equal(got, kozu.read_image(exr)), name)
            self.assertFalse(np.array_equal(got, denoised), name)

    def test_threads_do_not_change_the_image(self):
        one = kozu.render(scene_path("cornell"), spp=2, resolution=(32, 32), threads=1)
        two = kozu.render(scene_path("cornell"), spp=2, resolution=(32, 32), threads=2)
        self.assertTrue(np.array_equal(one, two))


class Errors(unittest.TestCase):
    def test_scene_error_names_file_and_json_path(self):
        scene = kozu.load(scene_path("cornell"))
        scene.dict["camera"]["fvo"] = 30
        with self.assertRaises(kozu.SceneError) as cm:
            kozu.render(scene, spp=1)
        self.assertEqual(cm.exception.file, scene_path("cornell"))
        self.assertEqual(cm.exception.json_path, "/camera/fvo")
        self.assertIn("did you mean 'fov'", str(cm.exception))
        self.assertIsInstance(cm.exception, ValueError)

    def test_dict_errors_name_the_dict(self):
        with self.assertRaises(kozu.SceneError) as cm:
            kozu.render({"camera": 5})
        self.assertEqual((cm.exception.file, cm.exception.json_path), ("<dict>", "/camera"))

    def test_missing_and_malformed_files(self):
        with self.assertRaises(kozu.SceneError) as cm:
            kozu.load(os.path.join(SCENES, "no-such-scene.json"))
        self.assertIn("no-such-scene.json", cm.exception.file)
        with self.assertRaises(kozu.SceneError):
            kozu.load(os.path.join(SOURCE, "README.md"))
        with self.assertRaises(kozu.SceneError):
            kozu.render(os.path.join(SCENES, "no-such-scene.json"))

    def test_bad_settings_name_the_argument(self):
        with self.assertRaises(kozu.RenderError) as cm:
            kozu.render(scene_path("cornell"), spp=-1)
        self.assertIn("spp", str(cm.exception))
        with self.assertRaises(kozu.RenderError) as cm:
            kozu.render(scene_path("cornell"), spp=1, aovs=["albedo", "colour"])
        self.assertIn("aovs", str(cm.exception))
        with self.assertRaises(kozu.RenderError) as cm:
            kozu.render(scene_path("cornell"), spp=1, denoise=True, denoiser="oidn")
        self.assertIn("kozu.render: denoiser: 'oidn': expected nlmeans (the default), regression, unet or ensemble",
                      str(cm.exception))
        with self.assertRaises(ValueError):  # JSON cannot hold NaN
            kozu.render({"render": {"spp": float("nan")}})


class Interaction(unittest.TestCase):
    def test_progress_reaches_one(self):
        seen = []
        kozu.render(scene_path("cornell"), spp=64, resolution=(96, 96), progress=seen.append)
        self.assertGreaterEqual(len(seen), 1)
        self.assertEqual(seen[-1], 1.0)
        self.assertEqual(seen, sorted(seen))
        self.assertTrue(all(0.0 <= f <= 1.0 for f in seen))

    def test_progress_exception_stops_the_render(self):
        def fail(_):
            raise ZeroDivisionError("from progress")
        start = time.monotonic()
        with self.assertRaises(ZeroDivisionError):
            kozu.render(scene_path("cornell"), spp=0, time_limit=30, resolution=(64, 64), progress=fail)
        self.assertLess(time.monotonic() - start, 10)

    def test_keyboard_interrupt_stops_the_render(self):
        timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
        start = time.monotonic()
        timer.start()
        try:
            with self.assertRaises(KeyboardInterrupt):
                kozu.render(scene_path("cornell"), spp=0, time_limit=30, resolution=(64, 64))
        finally:
            timer.cancel()
        self.assertLess(time.monotonic() - start, 10)
        # The module still renders afterwards.
        self.assertEqual(kozu.render(scene_path("cornell"), spp=1, resolution=(8, 8)).shape, (8, 8, 3))

    def test_gil_is_released_while_rendering(self):
        ticks = [0]
        stop = threading.Event()

        def count():
            while not stop.is_set():
                ticks[0] += 1
                time.sleep(0.001)
        t = threading.Thread(target=count)
        t.start()
        try:
            kozu.render(scene_path("cornell"), spp=0, time_limit=1.0, resolution=(64, 64))
        finally:
            stop.set()
            t.join()
        # About 1000 ticks in a second when the thread can run; none if the render held the GIL.
        self.assertGreater(ticks[0], 100)


class SceneCache(unittest.TestCase):
    def test_edit_and_render_again_without_reading_the_meshes(self):
        scene = kozu.load(scene_path("subsurface"))
        first = kozu.render(scene, spp=1, resolution=(32, 24))
        stats = scene.cache_stats()
        self.assertEqual(stats["hits"], 0)
        self.assertEqual(stats["misses"], 3)  # three PLY meshes
        scene.dict["materials"]["floor"]["albedo"] = [0.1, 0.9, 0.1]
        second = kozu.render(scene, spp=1, resolution=(32, 24))
        self.assertEqual(scene.cache_stats()["misses"], 3)
        self.assertEqual(scene.cache_stats()["hits"], 3)
        self.assertFalse(np.array_equal(first, second))

    def test_a_changed_file_is_read_again(self):
        tmp = tempfile.mkdtemp(prefix="kozu-py-cache-")
        try:
            shutil.copytree(os.path.join(SCENES, "meshes"), os.path.join(tmp, "meshes"))
            shutil.copy(scene_path("subsurface"), tmp)
            scene = kozu.load(os.path.join(tmp, "subsurface.json"))
            kozu.render(scene, spp=1, resolution=(16, 12))
            leaf = os.path.join(tmp, "meshes", "leaf.ply")
            st = os.stat(leaf)
            os.utime(leaf, ns=(st.st_atime_ns, st.st_mtime_ns + 1_000_000_000))
            kozu.render(scene, spp=1, resolution=(16, 12))
            self.assertEqual(scene.cache_stats()["misses"], 4)
            self.assertEqual(scene.cache_stats()["hits"], 2)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)


class Images(unittest.TestCase):
    def test_write_then_read_is_exact(self):
        tmp = tempfile.mkdtemp(prefix="kozu-py-img-")
        try:
            img = np.random.default_rng(3).random((7, 5, 3), dtype=np.float32) * 10
            path = os.path.join(tmp, "x.exr")
            kozu.write_image(path, img)
            self.assertTrue(np.array_equal(kozu.read_image(path), img))
            kozu.write_image(os.path.join(tmp, "x.png"), img)
            png = kozu.read_image(os.path.join(tmp, "x.png"))
            self.assertEqual(png.shape, (7, 5, 3))
            with self.assertRaises(ValueError):
                kozu.write_image(path, img[..., :2])
        finally:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    unittest.main()
