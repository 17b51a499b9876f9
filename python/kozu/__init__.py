"""kozu: a physically based renderer, from Python (docs/python.md).

    import kozu
    image = kozu.render("scenes/cornell.json", spp=64)   # float32 (H, W, 3), linear RGB

The module binds the renderer's library (src/); it adds no logic of its own.
"""
from ._kozu import (Bsdf, Medium, Phase, RenderError, Scene, SceneError,
                    __version__, demo, load, read_image, render,
                    write_image)

__all__ = ["Bsdf", "Medium", "Phase", "RenderError", "Scene", "SceneError",
           "__version__", "demo", "load", "read_image", "render", "write_image"]
