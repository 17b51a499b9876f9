"""kozu for Blender: export the open scene to kozu's scene format, and render with kozu as a render engine.

Enable with `addon_utils.enable("kozu_blender")` (with the repository's `blender/` folder on sys.path), or install
the zip that `python3 blender/make_zip.py` writes through Edit > Preferences > Add-ons > Install. docs/blender.md
says what maps to what.
"""
bl_info = {
    "name": "kozu",
    "author": "kozu developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "File > Export > kozu (.json); Render Engine: kozu",
    "description": "Export scenes to the kozu path tracer and render with it",
    "category": "Render",
}

if "bpy" in locals():  # a reload from Blender's F3 "Reload Scripts"
    import importlib
    from . import mapping, meshes, materials, export, engine  # noqa: F811
    for _m in (mapping, meshes, materials, export, engine):
        importlib.reload(_m)

import contextlib  # noqa: E402

import bpy  # noqa: E402
from bpy.props import BoolProperty, StringProperty  # noqa: E402
from bpy_extras.io_utils import ExportHelper  # noqa: E402

from . import engine, export  # noqa: E402


class KozuPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    kozu_path: StringProperty(name="kozu binary", subtype="FILE_PATH",
                              description="The kozu executable; empty: the KOZU environment variable, then PATH")

    def draw(self, context):
        self.layout.prop(self, "kozu_path")
        found = engine.find_kozu(context)
        self.layout.label(text=f"Using: {found}" if found else "kozu not found: set the path above")


@contextlib.contextmanager
def render_evaluation(scene):
    """The viewport depsgraph with the render's settings, as F12 would evaluate them: renderable objects hidden in
    the viewport shown, subdivision render levels, modifiers shown for rendering; restored afterwards."""
    saved, hidden = [], []
    for obj in scene.objects:
        if not obj.hide_render and (obj.hide_viewport or obj.hide_get()):
            hidden.append((obj, obj.hide_viewport, obj.hide_get()))
            obj.hide_viewport = False
            obj.hide_set(False)
        for mod in getattr(obj, "modifiers", []):
            saved.append((mod, "show_viewport", mod.show_viewport))
            mod.show_viewport = mod.show_render
            if mod.type == "SUBSURF":
                saved.append((mod, "levels", mod.levels))
                mod.levels = mod.render_levels
            elif mod.type == "MULTIRES":
                saved.append((mod, "levels", mod.levels))
                mod.levels = mod.render_levels
    try:
        yield
    finally:
        for mod, attr, value in reversed(saved):
            setattr(mod, attr, value)
        for obj, viewport, eye in hidden:
            obj.hide_viewport = viewport
            obj.hide_set(eye)


class EXPORT_SCENE_OT_kozu(bpy.types.Operator, ExportHelper):
    """Export the scene as a kozu scene (JSON, with PLY meshes beside it)"""
    bl_idname = "export_scene.kozu"
    bl_label = "Export kozu"
    bl_options = {"PRESET"}
    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})
    use_render_settings: BoolProperty(name="Render modifiers", default=True,
                                      description="Evaluate modifiers as a render does (subdivision render levels)")

    def execute(self, context):
        scene = context.scene
        manager = render_evaluation(scene) if self.use_render_settings else contextlib.nullcontext()
        try:
            with manager:
                depsgraph = context.evaluated_depsgraph_get()
                depsgraph.update()
                exporter = export.export_scene(depsgraph, self.filepath)
        except export.ExportError as e:
            self.report({"ERROR"}, f"kozu export: {e}")
            return {"CANCELLED"}
        c = exporter.counts
        summary = (f"kozu: wrote {self.filepath} ({c['meshes']} meshes, {c['instances']} instances, "
                   f"{c['triangles']} triangles, {c['lights']} lights)")
        if exporter.report.lines:
            self.report({"WARNING"}, summary + f"; {len(exporter.report.lines)} things not mapped exactly:\n"
                        + "\n".join(exporter.report.lines))
        else:
            self.report({"INFO"}, summary)
        return {"FINISHED"}


def _menu_export(self, context):
    self.layout.operator(EXPORT_SCENE_OT_kozu.bl_idname, text="kozu (.json)")


class RENDER_PT_kozu_sampling(bpy.types.Panel):
    """kozu reads Cycles' sampling settings; this panel shows them when kozu is the engine."""
    bl_label = "Sampling (kozu)"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    COMPAT_ENGINES = {"KOZU"}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        layout = self.layout
        cy = getattr(context.scene, "cycles", None)
        if cy is None:
            layout.label(text="Enable the Cycles add-on: kozu reads its sampling settings")
            return
        layout.use_property_split = True
        for prop in ("samples", "time_limit", "seed", "max_bounces", "use_adaptive_sampling", "adaptive_threshold"):
            if hasattr(cy, prop):
                layout.prop(cy, prop)
        layout.prop(context.scene.render, "film_transparent")


classes = (KozuPreferences, EXPORT_SCENE_OT_kozu, RENDER_PT_kozu_sampling)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.TOPBAR_MT_file_export.append(_menu_export)
    engine.register()


def unregister():
    engine.unregister()
    bpy.types.TOPBAR_MT_file_export.remove(_menu_export)
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
