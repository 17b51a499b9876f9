"""The exporter: Blender's evaluated scene (depsgraph) as a kozu scene file, meshes as PLY beside it.

export_scene(depsgraph, filepath) writes FILE.json and FILE_files/ (meshes, packed images, the spot profile) and
returns the Report of what was not mapped exactly (also written into the scene's `comment`). Instances (collection
instances, particle and geometry-nodes instances) become kozu `objects` placed by `instance` shapes, one mesh file
per instanced geometry however many times it is placed.
"""
import json
import math
import os
import shutil

from . import mapping
from .materials import ImageExporter, MaterialExporter, Report
from .meshes import mesh_arrays, write_ply

GEOMETRY_TYPES = {"MESH", "CURVE", "SURFACE", "META", "FONT", "CURVES"}


def _rows(m):
    return [[float(v) for v in row] for row in m]


def _det3(m):
    return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))


class Exporter:
    def __init__(self, depsgraph, filepath):
        self.depsgraph = depsgraph
        self.scene = depsgraph.scene_eval
        self.filepath = os.path.abspath(filepath)
        self.folder = os.path.dirname(self.filepath)
        stem = os.path.splitext(os.path.basename(self.filepath))[0]
        self.files_name = stem + "_files"
        self.files = os.path.join(self.folder, self.files_name)
        self.report = Report()
        self.images = ImageExporter(os.path.join(self.files, "textures"), self.report)
        self.materials = MaterialExporter(self.images, self.report)
        self.out = {"camera": None, "render": {}, "materials": {}, "media": {}, "objects": {}, "shapes": [],
                    "lights": []}
        self.material_names = {}  # Blender material name -> (kozu material name or None, emission, medium name)
        self.geometry = {}  # geometry key -> list of parts {file, material key}
        self.objects = {}  # geometry key -> kozu object name (None: every part emits)
        self.spot_profile = None
        self.portals = []  # (where, corners) of Cycles portal lights, attached to the environment after the world
        self.counts = {"meshes": 0, "instances": 0, "lights": 0, "triangles": 0}

    # --- file helpers ---------------------------------------------------------------------------------------

    def _rel(self, path):
        """A path as the scene refers to it: relative to the scene's folder when inside it."""
        path = os.path.abspath(path)
        rel = os.path.relpath(path, self.folder)
        return path if rel.startswith("..") else rel.replace(os.sep, "/")

    def _unique_file(self, sub, name):
        folder = os.path.join(self.files, sub)
        os.makedirs(folder, exist_ok=True)
        base, ext = os.path.splitext(mapping.sanitize_name(name))
        path, i = os.path.join(folder, base + ext), 1
        while os.path.exists(path):
            path, i = os.path.join(folder, f"{base}.{i}{ext}"), i + 1
        return path

    # --- materials ------------------------------------------------------------------------------------------

    def _material(self, material):
        """(kozu material name or None, emission or None, medium name or None) for a Blender material (or None)."""
        key = material.name_full if material is not None else None
        if key in self.material_names:
            return self.material_names[key]
        if material is None:
            name = "kozu_default"
            self.out["materials"][name] = {"type": "diffuse", "albedo": 0.8}
            result = (name, None, None)
        else:
            mat, emission, medium = self.materials.convert(material)
            name = medium_name = None
            if mat is not None:
                name = self._name(self.out["materials"], material.name)
                self.out["materials"][name] = self._relativize(mat)
            if medium is not None:
                medium_name = self._name(self.out["media"], material.name)
                self.out["media"][medium_name] = medium
            result = (name, emission, medium_name)
        self.material_names[key] = result
        return result

    @staticmethod
    def _name(table, name):
        name = name if name != "comment" else "comment_"
        out, i = name, 1
        while out in table:
            out, i = f"{name}.{i}", i + 1
        return out

    def _relativize(self, value):
        """Texture file paths in a material, relative to the scene where possible."""
        if isinstance(value, dict):
            return {k: (self._rel(v) if k == "file" and isinstance(v, str) else self._relativize(v))
                    for k, v in value.items()}
        return value

    # --- geometry -------------------------------------------------------------------------------------------

    def _geometry(self, obj, key):
        """Writes an evaluated object's geometry once per key: [(file, Blender material or None)]."""
        if key in self.geometry:
            return self.geometry[key]
        parts = []
        try:
            mesh = obj.to_mesh()
        except RuntimeError:
            mesh = None
        if mesh is None:
            self.geometry[key] = parts
            return parts
        try:
            arrays = mesh_arrays(mesh)
            for index, (pos, nrm, uv, tri) in sorted(arrays.items()):
                slots = obj.material_slots
                material = slots[index].material if index < len(slots) else None
                path = self._unique_file("meshes", f"{obj.data.name if obj.data else obj.name}.{index}.ply")
                write_ply(path, pos, nrm, uv, tri)
                self.counts["triangles"] += len(tri)
                parts.append((self._rel(path), material))
        finally:
            obj.to_mesh_clear()
        self.geometry[key] = parts
        return parts

    def _mesh_shape(self, file, material, matrix=None, camera_visible=True):
        name, emission, medium = self._material(material)
        shape = {"type": "mesh", "file": file, "skip_degenerate": True}
        if not camera_visible:
            shape["camera_visible"] = False
        if name is not None:
            shape["material"] = name
        if emission is not None:
            shape["emission"] = emission
        if medium is not None:
            shape["interior"] = medium
        if name is None and emission is None and medium is None:
            shape["material"] = self._material(None)[0]
        if matrix is not None:
            shape["transform"] = {"matrix": matrix}
        return shape

    def _add_object(self, inst, obj):
        matrix = mapping.to_kozu_matrix(_rows(inst.matrix_world))
        if abs(_det3(matrix)) < 1e-18:
            self.report.add(f"object '{obj.name}'", "scaled to zero: skipped")
            return
        if inst.is_instance:
            key = ("instance", obj.original.name_full if obj.original else obj.name,
                   obj.data.original.name_full if obj.data is not None and obj.data.original else "")
        else:
            key = ("object", obj.name_full)
        parts = self._geometry(obj, key)
        if not parts:
            return
        visible = getattr(obj, "visible_camera", True)
        if not inst.is_instance:
            for file, material in parts:
                self.out["shapes"].append(self._mesh_shape(file, material, matrix, visible))
            self.counts["meshes"] += 1
            return
        # An instance: its non-emitting parts are one kozu object; kozu's objects cannot emit, so emitting parts are
        # placed as meshes of their own.
        if not visible:
            self.report.add(f"object '{obj.name}'", "instances hidden from the camera are shown (kozu's instances "
                                                    "have no camera visibility)")
        object_name = self._object_name(key, obj, parts)
        if object_name is not None:
            self.out["shapes"].append({"type": "instance", "object": object_name, "transform": {"matrix": matrix}})
            self.counts["instances"] += 1
        for file, material in parts:
            if self._material(material)[1] is not None:
                self.out["shapes"].append(self._mesh_shape(file, material, matrix, visible))
                self.report.add(f"object '{obj.name}'", "emitting instances are exported as copies (kozu's "
                                                        "objects cannot emit)")

    def _object_name(self, key, obj, parts):
        cache = self.objects
        if key not in cache:
            shapes = [self._mesh_shape(file, material) for file, material in parts
                      if self._material(material)[1] is None]
            name = None
            if shapes:
                name = self._name(self.out["objects"], obj.name)
                self.out["objects"][name] = shapes
            cache[key] = name
        return cache[key]

    # --- volumes (OpenVDB objects) ----------------------------------------------------------------------------

    def _add_volume(self, inst, obj):
        where = f"volume '{obj.name}'"
        import bpy
        data = obj.data
        path = bpy.path.abspath(data.filepath, library=data.library) if data.filepath else ""
        if not path or not os.path.isfile(path):
            self.report.add(where, "no OpenVDB file on disk (packed or generated volumes are not exported): skipped")
            return
        if data.is_sequence:
            self.report.add(where, "an OpenVDB sequence: its first file used")
        material = obj.material_slots[0].material if len(obj.material_slots) else None
        coeffs = None
        if material is not None and material.use_nodes:
            out = MaterialExporter._output(material.node_tree)
            vol = out.inputs.get("Volume") if out is not None else None
            node = vol.links[0].from_node if vol is not None and vol.is_linked else None
            if node is not None:
                coeffs = self.materials.volume_coefficients(where, node)
                if node.bl_idname == "ShaderNodeVolumePrincipled":
                    attr = node.density_attribute if hasattr(node, "density_attribute") else "density"
                    if attr != "density":
                        self.report.add(where, f"density attribute '{attr}': kozu reads the grid 'density'")
        if coeffs is None:
            self.report.add(where, "no Principled Volume / Volume Scatter material: density 1, albedo 0.8 used")
            coeffs = ([1.0] * 3, [0.8] * 3, 0.0)
        st, al, g = coeffs
        scale = sum(st) / 3.0
        if max(st) - min(st) > 1e-6 * max(max(st), 1e-30):
            self.report.add(where, "chromatic extinction on a grid: kozu's grid medium takes their mean")
        matrix = mapping.to_kozu_matrix(_rows(inst.matrix_world))
        name = self._name(self.out["media"], obj.name)
        medium = {"type": "grid", "file": self._rel(path), "density_scale": scale,
                  "albedo": [min(max(a, 0.0), 1.0) for a in al], "transform": {"matrix": matrix}}
        if abs(g) > 1e-6:
            medium["phase"] = {"type": "hg", "g": min(max(g, -0.99), 0.99)}
        self.out["media"][name] = medium
        lo = [min(c[i] for c in obj.bound_box) for i in range(3)]
        hi = [max(c[i] for c in obj.bound_box) for i in range(3)]
        if not all(h > l for l, h in zip(lo, hi)):
            self.report.add(where, "empty bounds: skipped")
            return
        pos = [[(hi if (i >> a) & 1 else lo)[a] for a in range(3)] for i in range(8)]
        # Outward-facing triangles of the box (corner index bits: x = 1, y = 2, z = 4).
        idx = [0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4, 2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2,
               1, 3, 7, 1, 7, 5]
        self.out["shapes"].append({"type": "mesh", "positions": pos, "indices": idx, "interior": name,
                                   "transform": {"matrix": matrix}})

    # --- lights ---------------------------------------------------------------------------------------------

    def _add_light(self, inst, obj):
        light = obj.data
        where = f"light '{obj.name}'"
        m = mapping.to_kozu_matrix(_rows(inst.matrix_world))
        colour = [float(c) for c in light.color]
        power = float(light.energy)
        if light.use_nodes:
            self.report.add(where, "light nodes are not evaluated: colour x power used")
        position = mapping.transform_point(m, [0.0, 0.0, 0.0])
        axis = mapping.normalize(mapping.transform_direction(m, [0.0, 0.0, -1.0]))
        self.counts["lights"] += 1
        if light.type == "POINT":
            radius = float(light.shadow_soft_size)
            if radius > 0.0:
                # Cycles 3.4's point light of radius r is a sphere of that radius seen from everywhere.
                self.out["shapes"].append({"type": "sphere", "center": position, "radius": radius,
                                           "emission": mapping.sphere_light_radiance(power, colour, radius),
                                           "camera_visible": False})
            else:
                self.out["lights"].append({"type": "point", "position": position,
                                           "intensity": mapping.point_light_intensity(power, colour)})
        elif light.type == "SPOT":
            cone, falloff = mapping.spot_angles(float(light.spot_size), float(light.spot_blend))
            if light.shadow_soft_size > 0.0:
                self.report.add(where, f"spot radius {light.shadow_soft_size:.3g}: kozu's spot is a point (hard "
                                       "shadows)")
            self.out["lights"].append({"type": "spot", "position": position, "direction": axis,
                                       "intensity": mapping.point_light_intensity(power, colour),
                                       "cone_angle": cone, "falloff_angle": falloff,
                                       "profile": self._spot_profile()})
        elif light.type == "SUN":
            self.out["lights"].append({"type": "directional", "direction": axis,
                                       "irradiance": [power * c for c in colour],
                                       "angular_diameter": min(math.degrees(float(light.angle)), 180.0)})
        elif light.type == "AREA" and getattr(getattr(light, "cycles", None), "is_portal", False):
            # Cycles' portal: no light of its own; where the world enters (a window). kozu's portals are rectangles
            # on the environment, front (Cycles' light direction, local -z) into the scene.
            sx = float(light.size)
            sy = float(light.size_y) if light.shape in ("RECTANGLE", "ELLIPSE") else sx
            if light.shape in ("DISK", "ELLIPSE"):
                self.report.add(where, f"{light.shape.lower()} portal: its bounding rectangle used")
            self.counts["lights"] -= 1
            self.portals.append((where, [mapping.transform_point(m, v) for v in mapping.rectangle(sx, sy)]))
        elif light.type == "AREA":
            sx = float(light.size)
            sy = float(light.size_y) if light.shape in ("RECTANGLE", "ELLIPSE") else sx
            local = (mapping.rectangle(sx, sy) if light.shape in ("SQUARE", "RECTANGLE")
                     else mapping.ellipse_polygon(sx, sy))
            verts = [mapping.transform_point(m, v) for v in local]
            area = mapping.polygon_area(verts)
            if not area > 0.0:
                self.report.add(where, "zero area: skipped")
                return
            spread = getattr(light, "spread", math.pi)
            if spread < math.pi - 1e-4:
                self.report.add(where, f"spread {math.degrees(spread):.3g} deg: kozu's area lights emit over the "
                                       "whole hemisphere")
            shape = {"type": "quad" if len(verts) == 4 else "polygon", "vertices": verts,
                     "emission": mapping.area_light_radiance(power, colour, area), "camera_visible": False}
            self.out["shapes"].append(shape)
        else:
            self.report.add(where, f"light type {light.type} not mapped: skipped")

    def _attach_portals(self):
        """Cycles' portal lights become the environment's "portals" (at most 16, as kozu reads them)."""
        env = next((light for light in self.out["lights"] if light["type"] == "environment"), None)
        for i, (where, corners) in enumerate(self.portals):
            if env is None:
                self.report.add(where, "portal without a world to let in: skipped")
            elif i >= 16:
                self.report.add(where, "more than 16 portals: skipped")
            else:
                env.setdefault("portals", []).append({"vertices": corners})

    def _spot_profile(self):
        if self.spot_profile is None:
            path = os.path.join(self.files, "spot_cosine.ies")
            os.makedirs(self.files, exist_ok=True)
            with open(path, "w") as f:
                f.write(mapping.cosine_profile_ies())
            self.spot_profile = self._rel(path)
        return self.spot_profile

    # --- world, camera, settings ----------------------------------------------------------------------------

    def _world(self):
        world = self.scene.world
        where = "world"
        if world is None:
            return
        if not world.use_nodes or world.node_tree is None:
            c = [float(v) for v in world.color]
            if max(c) > 0.0:
                self.out["lights"].append({"type": "environment", "radiance": c})
            return
        outs = [n for n in world.node_tree.nodes if n.bl_idname == "ShaderNodeOutputWorld"
                and n.target in ("ALL", "CYCLES")]
        out = ([n for n in outs if n.is_active_output] or outs or [None])[0]
        if out is None or not out.inputs["Surface"].is_linked:
            return
        bg = out.inputs["Surface"].links[0].from_node
        if out.inputs.get("Volume") is not None and out.inputs["Volume"].is_linked:
            self.report.add(where, "world volume not mapped: dropped")
        if bg.bl_idname != "ShaderNodeBackground":
            self.report.add(where, f"world shader '{bg.name}' ({bg.bl_idname}) not mapped: no environment")
            return
        strength = float(bg.inputs["Strength"].default_value)
        if bg.inputs["Strength"].is_linked:
            self.report.add(where, "background strength driven by nodes: its unlinked value used")
        col = bg.inputs["Color"]
        if not col.is_linked:
            c = [float(v) * strength for v in list(col.default_value)[:3]]
            if max(c) > 0.0:
                self.out["lights"].append({"type": "environment", "radiance": c})
            return
        tex = col.links[0].from_node
        if tex.bl_idname != "ShaderNodeTexEnvironment" or tex.image is None:
            self.report.add(where, f"background colour from '{tex.name}' ({tex.bl_idname}) not mapped: its "
                                   "unlinked colour used")
            c = [float(v) * strength for v in list(col.default_value)[:3]]
            self.out["lights"].append({"type": "environment", "radiance": c})
            return
        if tex.projection != "EQUIRECTANGULAR":
            self.report.add(where, f"environment projection {tex.projection}: read as equirectangular")
        rot_z = 0.0
        vec = tex.inputs["Vector"]
        if vec.is_linked:
            node = vec.links[0].from_node
            if node.bl_idname == "ShaderNodeMapping":
                r = [float(v) for v in node.inputs["Rotation"].default_value]
                if abs(r[0]) > 1e-6 or abs(r[1]) > 1e-6:
                    self.report.add(where, "environment mapping rotates about x or y: only its z rotation kept")
                rot_z = r[2] if node.vector_type != "TEXTURE" else -r[2]
            elif node.bl_idname != "ShaderNodeTexCoord":
                self.report.add(where, f"environment coordinates from '{node.name}' not mapped")
        path = self.images.path(tex.image, where)
        if path is None:
            return
        cs, exact = mapping.texture_colorspace(tex.image.colorspace_settings.name, tex.image.is_float)
        env = {"type": "environment", "file": self._rel(path), "colorspace": cs,
               "rotate": mapping.environment_rotate(rot_z)}
        if strength != 1.0:
            env["scale"] = max(strength, 0.0)
        self.out["lights"].append(env)

    def _camera(self, width, height):
        cam_obj = self.scene.camera
        if cam_obj is None:
            raise ExportError("the scene has no active camera")
        cam_obj = cam_obj.evaluated_get(self.depsgraph)
        cam = cam_obj.data
        where = f"camera '{cam_obj.name}'"
        m = mapping.rigid(mapping.to_kozu_matrix(_rows(cam_obj.matrix_world)))
        out = {"transform": {"matrix": m}, "resolution": [width, height]}
        if cam.type == "PERSP":
            out["fov"] = mapping.vertical_fov(cam.lens, cam.sensor_width, cam.sensor_height, cam.sensor_fit,
                                              width, height)
        elif cam.type == "ORTHO":
            out["type"] = "orthographic"
            out["scale"] = mapping.orthographic_height(cam.ortho_scale, cam.sensor_fit, width, height)
        else:
            pano = getattr(cam, "panorama_type", None) or getattr(getattr(cam, "cycles", None), "panorama_type", "")
            if pano != "EQUIRECTANGULAR":
                self.report.add(where, f"panoramic camera {pano}: rendered as kozu's equirectangular panorama")
            out["type"] = "panorama"
        if abs(cam.shift_x) > 1e-6 or abs(cam.shift_y) > 1e-6:
            self.report.add(where, "lens shift not mapped: the image is centred")
        s = self.scene.render
        if abs(s.pixel_aspect_x - s.pixel_aspect_y) > 1e-6:
            self.report.add(where, "non-square pixel aspect not mapped")
        if cam.dof.use_dof and cam.type in ("PERSP", "ORTHO"):
            if cam.dof.focus_object is not None:
                focus = cam.dof.focus_object.evaluated_get(self.depsgraph).matrix_world.translation
                eye = cam_obj.matrix_world.translation
                fwd = -cam_obj.matrix_world.to_3x3().normalized().col[2]
                dist = max((focus - eye).dot(fwd), 1e-6)
            else:
                dist = max(float(cam.dof.focus_distance), 1e-6)
            if cam.type == "PERSP":
                out["type"] = "thinlens"
                out["aperture_radius"] = mapping.aperture_radius(cam.lens, cam.dof.aperture_fstop)
                out["focus_distance"] = dist
            else:
                self.report.add(where, "depth of field on an orthographic camera: not mapped")
            if cam.dof.aperture_blades > 0:
                self.report.add(where, "aperture blades: kozu's aperture is round")
        self.out["camera"] = out

    def _settings(self):
        s = self.scene.render
        width, height = mapping.render_resolution(s.resolution_x, s.resolution_y, s.resolution_percentage)
        render = {}
        cy = getattr(self.scene, "cycles", None)
        if cy is not None:
            render["spp"] = int(cy.samples)
            render["max_depth"] = mapping.max_depth(cy.max_bounces)
            render["seed"] = int(cy.seed)
            limit = float(getattr(cy, "time_limit", 0.0))
            if limit > 0.0:
                render["time_limit"] = limit
            flt, exact = mapping.pixel_filter(getattr(cy, "pixel_filter_type", "BLACKMAN_HARRIS"),
                                              float(getattr(cy, "filter_width", 1.5)))
            render["filter"] = flt
            if not exact:
                self.report.add("render", "pixel filter: kozu's nearest (Gaussian sigma 0.5 or 1-pixel box)")
            lower = [k for k in ("diffuse_bounces", "glossy_bounces", "transmission_bounces", "volume_bounces")
                     if getattr(cy, k, cy.max_bounces) < cy.max_bounces]
            if lower:
                self.report.add("render", "Cycles limits " + ", ".join(f"{k} to {getattr(cy, k)}" for k in lower)
                                + f"; kozu limits every path to {cy.max_bounces} bounces alike")
            if getattr(cy, "use_denoising", False):
                self.report.add("render", "Cycles denoising on: render with kozu's --denoise")
            if getattr(cy, "use_adaptive_sampling", False):
                render["noise_threshold"] = float(cy.adaptive_threshold)
                if getattr(cy, "adaptive_min_samples", 0) > 0:
                    render["min_spp"] = max(int(cy.adaptive_min_samples), 2)
        else:
            self.report.add("render", "the Cycles add-on is off: kozu's default samples and bounces used")
        self.out["render"] = render
        return width, height

    def command_line(self):
        """What kozu's command takes beyond the scene for Blender's film and colour settings."""
        args = []
        s = self.scene
        tm, exact = mapping.tonemap(s.view_settings.view_transform)
        args += ["--tonemap", tm]
        if not exact:
            self.report.add("colour management", f"view transform '{s.view_settings.view_transform}' as kozu's "
                                                 f"'{tm}' tone map (8-bit outputs; EXRs are scene-linear)")
        if s.view_settings.look not in ("None", ""):
            self.report.add("colour management", f"look '{s.view_settings.look}' not mapped")
        if abs(s.view_settings.exposure) > 1e-6:
            args += ["--exposure", f"{s.view_settings.exposure:g}"]
        if s.render.film_transparent:
            args += ["--alpha"]
        return args

    # --- the whole scene ------------------------------------------------------------------------------------

    def _fresh_files_folder(self):
        """Removes the files a previous export to the same path wrote (only a folder this exporter marked), so a
        re-export leaves no stale meshes; then marks the folder."""
        marker = os.path.join(self.files, ".kozu_blender")
        if os.path.isdir(self.files) and os.path.isfile(marker):
            shutil.rmtree(self.files)
        os.makedirs(self.files, exist_ok=True)
        with open(marker, "w") as f:
            f.write("written by kozu_blender; removed and rewritten by the next export to the same scene path\n")

    def run(self):
        self._fresh_files_folder()
        width, height = self._settings()
        self._camera(width, height)
        self._world()
        for inst in self.depsgraph.object_instances:
            obj = inst.object
            original = obj.original if obj.original is not None else obj
            if not inst.is_instance and _render_hidden(original):
                continue
            if obj.type in GEOMETRY_TYPES:
                self._add_object(inst, obj)
            elif obj.type == "LIGHT":
                self._add_light(inst, obj)
            elif obj.type == "VOLUME":
                self._add_volume(inst, obj)
        self._attach_portals()
        args = self.command_line()
        if self.scene.render.film_transparent:
            # Cycles' transparent film: the world lights the scene but is not seen; kozu's coverage goes to alpha.
            for light in self.out["lights"]:
                if light["type"] == "environment":
                    light["camera_visible"] = False
        if not self.out["shapes"]:
            raise ExportError("nothing to render: the scene has no visible geometry or area lights")
        scene = {"comment": {"exported_by": "kozu_blender", "blend_file": _blend_file(),
                             "render_with": ["kozu", "render", os.path.basename(self.filepath)] + args,
                             "not_mapped_exactly": self.report.lines}}
        for k in ("camera", "render", "materials", "media", "objects", "shapes", "lights"):
            if self.out[k] or k in ("camera", "shapes"):
                scene[k] = self.out[k]
        tmp = self.filepath + ".tmp"
        with open(tmp, "w") as f:
            json.dump(scene, f, indent=1)
        os.replace(tmp, self.filepath)
        self.args = args
        return self


def _render_hidden(obj):
    """Disabled in renders, itself or through every collection it is in (the viewport depsgraph still has it)."""
    if getattr(obj, "hide_render", False):
        return True
    collections = [c for c in getattr(obj, "users_collection", []) if hasattr(c, "hide_render")]
    return bool(collections) and all(c.hide_render for c in collections)


class ExportError(Exception):
    """An export that cannot produce a scene (no camera, nothing to render)."""


def _blend_file():
    import bpy
    return bpy.data.filepath or "(unsaved)"


def export_scene(depsgraph, filepath):
    """Writes the scene; returns the Exporter (its .report lines, .args for kozu's command, .counts)."""
    return Exporter(depsgraph, filepath).run()
