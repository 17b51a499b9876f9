"""Renders one bench/cycles scene with Cycles inside Blender and prints its render time (compare.py runs this):
    blender -b --factory-startup --python bench/cycles/blender_render.py -- SCENE RES SPP SEED DEPTH THREADS OUT.exr [VDB]
"""
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bpy  # noqa: E402
import scenes  # noqa: E402

args = sys.argv[sys.argv.index("--") + 1:]
name, res, spp, seed, depth, threads, out = args[0], *map(int, args[1:6]), args[6]
scenes.blender_scene(name, res, spp, seed, depth, threads, args[7] if len(args) > 7 else None)
bpy.context.scene.render.filepath = out
start = time.perf_counter()
bpy.ops.render.render(write_still=True)
print(f"CYCLES_RENDER_SECONDS {time.perf_counter() - start:.4f}")
