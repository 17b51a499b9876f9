"""Blender materials (Cycles shader node trees) as kozu materials, emission and media.

Read from the active Material Output's Surface and Volume sockets:
  Principled BSDF            -> `standard` (or `subsurface` when its subsurface weight is on), emission on the shape
  Diffuse / Glossy / Glass   -> `diffuse` / `conductor` or metallic `standard` / `dielectric` or transmissive
                                `standard` (tinted glass)
  Subsurface Scattering      -> `subsurface`
  Emission (alone, or added) -> the shape's `emission` (radiance = colour x strength, as Cycles shows it)
  Transparent BSDF           -> `opacity` 0
  Image Texture (+ Mapping, Separate RGB/Color, Normal Map, Bump) on any input -> kozu image textures
  Principled Volume, Volume Scatter, Volume Absorption (and their sum) -> a `homogeneous` medium inside the mesh
Anything else is reported (Report) with what was used instead, never dropped silently.
"""
import os

from . import mapping


class Report:
    """What the export could not map exactly: shown in Blender's info area and written to the scene's `comment`."""

    def __init__(self):
        self.lines = []

    def add(self, where, what):
        line = f"{where}: {what}"
        if line not in self.lines:
            self.lines.append(line)

    def __len__(self):
        return len(self.lines)


def _linked(socket):
    """(node, output socket) feeding `socket`, following reroutes; (None, None) when unlinked."""
    if socket is None or not socket.is_linked:
        return None, None
    link = socket.links[0]
    node, out = link.from_node, link.from_socket
    while node.bl_idname == "NodeReroute":
        if not node.inputs[0].is_linked:
            return None, None
        link = node.inputs[0].links[0]
        node, out = link.from_node, link.from_socket
    if not link.is_valid or getattr(link, "is_muted", False) or node.mute:
        return None, None
    return node, out


def _input(node, *names):
    """The first input socket of `node` with one of `names` (Principled v1 names in Blender 3.x, v2 in 4.x)."""
    for name in names:
        s = node.inputs.get(name)
        if s is not None:
            return s
    return None


def _value(socket, default=0.0):
    if socket is None:
        return default
    v = socket.default_value
    try:
        return [float(c) for c in v][:3]
    except TypeError:
        return float(v)


class MaterialExporter:
    """Converts materials once each; `images` places image files for the scene (ImageExporter in export.py)."""

    def __init__(self, images, report):
        self.images = images
        self.report = report

    # --- inputs ---------------------------------------------------------------------------------------------

    def _texture(self, where, node, out):
        """A kozu image texture for an Image Texture node's output (or through Separate RGB/Color), else None."""
        channel = None
        if node.bl_idname in ("ShaderNodeSeparateRGB", "ShaderNodeSeparateColor"):
            if getattr(node, "mode", "RGB") != "RGB":
                self.report.add(where, f"'{node.name}' separates {node.mode}, not RGB; its input's first channel used")
            channel = {"R": "r", "Red": "r", "G": "g", "Green": "g", "B": "b", "Blue": "b"}.get(out.name, "r")
            node, out = _linked(node.inputs[0])
            if node is None:
                return None
        if node.bl_idname != "ShaderNodeTexImage":
            return None
        if node.image is None:
            self.report.add(where, f"image texture '{node.name}' has no image; its input's default used")
            return None
        tex = self.images.texture(node.image, where)
        if tex is None:
            return None
        if out.name == "Alpha":
            channel = "a"
        if channel:
            tex["channel"] = channel
        if node.interpolation == "Closest":
            tex["filter"] = "closest"
        if node.extension != "REPEAT":
            self.report.add(where, f"image '{node.image.name}' extension {node.extension}: kozu repeats textures")
        if node.projection != "FLAT":
            self.report.add(where, f"image '{node.image.name}' projection {node.projection}: kozu uses the mesh's UVs")
        vec, _ = _linked(node.inputs.get("Vector"))
        if vec is not None:
            self._uv_transform(where, vec, tex)
        return tex

    def _uv_transform(self, where, node, tex):
        if node.bl_idname == "ShaderNodeTexCoord" or node.bl_idname == "ShaderNodeUVMap":
            return
        if node.bl_idname != "ShaderNodeMapping" or node.vector_type not in ("POINT", "TEXTURE"):
            self.report.add(where, f"texture coordinates from '{node.name}' ({node.bl_idname}): the mesh's UVs used")
            return
        loc, rot, scale = (_value(node.inputs.get(n)) for n in ("Location", "Rotation", "Scale"))
        if node.vector_type == "TEXTURE":  # the inverse transform
            self.report.add(where, f"mapping '{node.name}' of type TEXTURE: inverted as a POINT mapping")
            scale = [1.0 / s if s else 1.0 for s in scale]
            loc, rot = [-c for c in loc], [-c for c in rot]
        if abs(rot[0]) > 1e-6 or abs(rot[1]) > 1e-6:
            self.report.add(where, f"mapping '{node.name}' rotates about x or y: only its z rotation kept")
        if scale[:2] != [1.0, 1.0]:
            tex["uv_scale"] = scale[:2]
        if abs(rot[2]) > 1e-9:
            tex["uv_rotation"] = rot[2]
        if loc[:2] != [0.0, 0.0]:
            tex["uv_offset"] = loc[:2]

    def _param(self, where, socket, default=None):
        """An input as a kozu value or texture: its texture when an image feeds it, else its default value."""
        if socket is None:
            return default
        node, out = _linked(socket)
        if node is not None:
            tex = self._texture(f"{where} {socket.name}", node, out)
            if tex is not None:
                return tex
            self.report.add(where, f"input '{socket.name}' is driven by '{node.name}' ({node.bl_idname}), which "
                                   "kozu does not evaluate: its unlinked value used")
        return _value(socket, default)

    def _data_texture(self, where, node, socket, what):
        """The image feeding `node`'s input `socket`, read as data (linear), or None (reported)."""
        src, out = _linked(node.inputs.get(socket))
        tex = self._texture(f"{where} {what}", src, out) if src is not None else None
        if tex is None:
            self.report.add(where, f"{what} '{node.name}' is not fed by an image texture: dropped")
            return None
        tex["colorspace"] = "linear"
        return tex

    def _normal(self, where, node_socket, mat):
        """A Normal input fed by a tangent-space Normal Map node or a Bump node, into kozu's keys on `mat`."""
        node, _ = _linked(node_socket)
        if node is None:
            return
        if node.bl_idname == "ShaderNodeNormalMap":
            if node.space != "TANGENT":
                self.report.add(where, f"normal map '{node.name}' in {node.space} space: kozu reads tangent space only")
                return
            tex = self._data_texture(where, node, "Color", "normal map")
            if tex is None:
                return
            mat["normal_map"] = tex
            strength = _value(node.inputs.get("Strength"), 1.0)
            if strength != 1.0:
                mat["normal_map_strength"] = max(strength, 0.0)
        elif node.bl_idname == "ShaderNodeBump":
            tex = self._data_texture(where, node, "Height", "bump")
            if tex is None:
                return
            mat["bump_map"] = tex
            mat["bump_scale"] = (_value(node.inputs.get("Distance"), 1.0) * _value(node.inputs.get("Strength"), 1.0)
                                 * (-1.0 if node.invert else 1.0))
            self.report.add(where, f"bump '{node.name}': kozu's bump_scale = distance x strength (approximate)")
        else:
            self.report.add(where, f"normal from '{node.name}' ({node.bl_idname}) not mapped: dropped")

    # --- surfaces -------------------------------------------------------------------------------------------

    def convert(self, material):
        """(kozu material dict or None, emission rgb or None, medium dict or None) for a Blender material."""
        where = f"material '{material.name}'"
        if not material.use_nodes or material.node_tree is None:
            c = list(material.diffuse_color)[:3]
            return {"type": "diffuse", "albedo": c}, None, None
        out = self._output(material.node_tree)
        if out is None:
            self.report.add(where, "no Material Output node: grey diffuse used")
            return {"type": "diffuse", "albedo": 0.8}, None, None
        surface, _ = _linked(out.inputs.get("Surface"))
        volume, _ = _linked(out.inputs.get("Volume"))
        if out.inputs.get("Displacement") is not None and out.inputs["Displacement"].is_linked:
            self.report.add(where, "displacement is not exported (kozu displaces nothing)")
        medium = self.medium(where, volume) if volume is not None else None
        if surface is None:
            # A volume alone: Cycles' surface is then invisible, as kozu's boundary without a material.
            return (None, None, medium) if medium is not None else ({"type": "diffuse", "albedo": 0.0}, None, None)
        mat, emission = self._shader(where, surface)
        return mat, emission, medium

    @staticmethod
    def _output(tree):
        outs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial" and n.target in ("ALL", "CYCLES")]
        active = [n for n in outs if n.is_active_output]
        return (active or outs or [None])[0]

    def _shader(self, where, node):
        """(material, emission) for a surface shader node."""
        kind = node.bl_idname
        if kind == "ShaderNodeBsdfPrincipled":
            return self._principled(where, node)
        if kind == "ShaderNodeEmission":
            return None, self._emission(where, node.inputs["Color"], node.inputs["Strength"])
        if kind == "ShaderNodeBsdfDiffuse":
            if _value(node.inputs.get("Roughness"), 0.0) > 0.0:
                self.report.add(where, "Diffuse BSDF roughness (Oren-Nayar) > 0: kozu's Lambert used")
            return self._with_normal(where, node, {"type": "diffuse",
                                                   "albedo": self._param(where, node.inputs["Color"])}), None
        if kind in ("ShaderNodeBsdfGlossy", "ShaderNodeBsdfAnisotropic"):
            return self._with_normal(where, node, self._glossy(where, node)), None
        if kind == "ShaderNodeBsdfGlass":
            return self._with_normal(where, node, self._glass(where, node)), None
        if kind == "ShaderNodeSubsurfaceScattering":
            mfp = [r * _value(node.inputs["Scale"], 1.0) for r in _value(node.inputs["Radius"], [1.0, 0.2, 0.1])]
            return {"type": "subsurface", "albedo": self._param(where, node.inputs["Color"]),
                    "mfp": [max(m, 1e-6) for m in mfp], "ior": max(_value(node.inputs.get("IOR"), 1.4), 1.0001)}, None
        if kind == "ShaderNodeBsdfTransparent":
            return {"type": "diffuse", "albedo": 0.0, "opacity": 0.0}, None
        if kind == "ShaderNodeAddShader":
            return self._combine(where, node, add=True)
        if kind == "ShaderNodeMixShader":
            return self._combine(where, node, add=False)
        self.report.add(where, f"shader '{node.name}' ({kind}) has no kozu model: grey diffuse used")
        return {"type": "diffuse", "albedo": 0.8}, None

    def _with_normal(self, where, node, mat):
        self._normal(where, node.inputs.get("Normal"), mat)
        return mat

    def _combine(self, where, node, add):
        """Add/Mix: a BSDF with an Emission keeps both; other combinations keep the heavier shader (reported)."""
        shaders = [_linked(s)[0] for s in node.inputs if s.type == "SHADER"]
        fac = 0.5 if add else _value(node.inputs.get("Fac"), 0.5)
        weights = [1.0, 1.0] if add else [1.0 - fac, fac]
        parts = [(self._shader(where, s) if s is not None else (None, None), w) for s, w in zip(shaders, weights)]
        mats = [(m, w) for (m, e), w in parts if m is not None and w > 0.0]
        emission = None
        for (m, e), w in parts:
            if e is not None and w > 0.0:
                e = [c * w for c in e]
                emission = e if emission is None else [a + b for a, b in zip(emission, e)]
        if len(mats) > 1:
            self.report.add(where, f"'{node.name}' mixes two BSDFs: kozu keeps the heavier one")
            mats.sort(key=lambda mw: -mw[1])
        if not add and len(mats) == 1 and mats[0][1] < 1.0:
            self.report.add(where, f"'{node.name}' mixes a BSDF at weight {mats[0][1]:.3g} with a non-BSDF: "
                                   "the BSDF kept at full weight")
        return (mats[0][0] if mats else None), emission

    def _emission(self, where, colour, strength):
        node, _ = _linked(colour)
        if node is not None:
            self.report.add(where, f"emission colour driven by '{node.name}': kozu meshes emit one colour, its "
                                   "unlinked value used")
        c = _value(colour, [1.0, 1.0, 1.0])
        s = _value(strength, 1.0)
        e = [max(v * s, 0.0) for v in c]
        return e if max(e) > 0.0 else None

    def _principled(self, where, node):
        inp = lambda *names: _input(node, *names)  # noqa: E731
        mat = {"type": "standard"}
        base = self._param(where, inp("Base Color"), [0.8, 0.8, 0.8])
        metallic = self._param(where, inp("Metallic"), 0.0)
        roughness = self._param(where, inp("Roughness"), 0.5)
        transmission = self._param(where, inp("Transmission", "Transmission Weight"), 0.0)
        v1 = inp("Specular") is not None  # Blender 3.x's Principled v1
        if v1:
            specular = _value(inp("Specular"), 0.5)
            ior = _value(inp("IOR"), 1.45)
            tint = _value(inp("Specular Tint"), 0.0)
            if tint > 0.0:
                self.report.add(where, "Principled Specular Tint > 0: not mapped (kozu's coat is untinted)")
            # v1 reflects F0 = 0.08 specular on opaque surfaces and uses IOR only for transmission.
            transmissive = isinstance(transmission, dict) or transmission > 0.0
            mat["ior"] = min(max(ior, 1.0), 3.0) if transmissive else mapping.ior_from_specular(specular)
            if transmissive and abs(mapping.ior_from_specular(specular) - mat["ior"]) > 0.05:
                self.report.add(where, f"transmission with Specular {specular:.3g}: kozu reflects by IOR "
                                       f"{mat['ior']:.3g} alone")
        else:  # v2: IOR for both, Specular IOR Level scales F0 (0.5 = as the IOR says)
            ior = _value(inp("IOR"), 1.5)
            mat["ior"] = min(max(ior, 1.0), 3.0)
            level = _value(inp("Specular IOR Level"), 0.5)
            if abs(level - 0.5) > 1e-6:
                mat["specular"] = min(max(2.0 * level, 0.0), 1.0)
            tint = _value(inp("Specular Tint"), [1.0, 1.0, 1.0])
            if isinstance(tint, list) and tint != [1.0, 1.0, 1.0]:
                mat["specular_color"] = [min(max(c, 0.0), 1.0) for c in tint]
        if getattr(node, "distribution", "") == "GGX" and (isinstance(roughness, dict) or roughness > 0.3):
            self.report.add(where, "Principled GGX loses rough surfaces' multiply scattered light; kozu's standard "
                                   "keeps it (as Multiscatter GGX), so they render brighter")
        mat["base_color"] = base
        if metallic != 0.0:
            mat["metallic"] = metallic
        mat["roughness"] = roughness
        if transmission != 0.0:
            mat["transmission"] = transmission
            tr = _value(inp("Transmission Roughness"), 0.0)
            if tr > 0.0:
                self.report.add(where, "Principled Transmission Roughness: kozu's transmission uses Roughness")
        coat = self._param(where, inp("Clearcoat", "Coat Weight"), 0.0)
        if coat != 0.0:
            mat["clearcoat"] = coat
            mat["clearcoat_roughness"] = self._param(where, inp("Clearcoat Roughness", "Coat Roughness"), 0.03)
        sheen = _value(inp("Sheen", "Sheen Weight"), 0.0)
        if sheen > 0.0:
            if v1:
                t = _value(inp("Sheen Tint"), 0.5)
                b = base if isinstance(base, list) else [0.8, 0.8, 0.8]
                lum = max(mapping.luminance(b), 1e-6)
                tint_rgb = [c / lum for c in b]
                mat["sheen_color"] = [min(sheen * ((1 - t) + t * c), 1.0) for c in tint_rgb]
                self.report.add(where, "Principled v1 sheen (Disney's) as kozu's Charlie sheen: approximate")
            else:
                tint_rgb = _value(inp("Sheen Tint"), [1.0, 1.0, 1.0])
                mat["sheen_color"] = [min(sheen * c, 1.0) for c in tint_rgb]
                mat["sheen_roughness"] = _value(inp("Sheen Roughness"), 0.5)
        if abs(_value(inp("Anisotropic"), 0.0)) > 0.0:
            self.report.add(where, "Principled Anisotropic: not mapped (kozu's standard is isotropic)")
        alpha = self._param(where, inp("Alpha"), 1.0)
        if alpha != 1.0:
            mat["opacity"] = alpha
        self._normal(where, inp("Normal"), mat)
        if inp("Clearcoat Normal", "Coat Normal") is not None and inp("Clearcoat Normal", "Coat Normal").is_linked:
            self.report.add(where, "clearcoat normal: kozu's coat uses the base normal")
        emission = self._emission(where, inp("Emission", "Emission Color"), inp("Emission Strength"))

        sss = _value(inp("Subsurface", "Subsurface Weight"), 0.0)
        if sss > 0.0:
            if metallic != 0.0 or transmission != 0.0 or coat != 0.0 or sheen > 0.0:
                self.report.add(where, "subsurface with metallic, transmission, coat or sheen: kozu's standard "
                                       "used, without subsurface")
            else:
                return self._principled_subsurface(where, node, mat, sss, v1), emission
        return mat, emission

    def _principled_subsurface(self, where, node, mat, weight, v1):
        """Principled subsurface as kozu's `subsurface`: albedo and mean free path as Cycles' random walk takes
        them (v1: colour = mix(base, subsurface colour, weight), radius x weight; v2: base colour, radius x
        scale); kozu's boundary keeps the Principled specular's index and roughness."""
        radius = _value(_input(node, "Subsurface Radius"), [1.0, 0.2, 0.1])
        base = mat["base_color"]
        if v1:
            sc = self._param(where, _input(node, "Subsurface Color"), [0.8, 0.8, 0.8])
            if isinstance(sc, dict) or isinstance(base, dict):
                albedo = sc if weight >= 0.5 else base
                if weight < 1.0:
                    self.report.add(where, "textured subsurface colour mixed by weight: the heavier one used")
            else:
                albedo = [weight * s + (1.0 - weight) * b for s, b in zip(sc, base)]
            mfp = [r * weight for r in radius]
        else:
            albedo = base
            mfp = [r * _value(_input(node, "Subsurface Scale"), 0.05) for r in radius]
            if weight < 1.0:
                self.report.add(where, f"subsurface weight {weight:.3g} < 1: kozu's subsurface is all subsurface")
        self.report.add(where, "subsurface: Cycles' random walk as kozu's Christensen-Burley profile (differs on "
                               "thin parts)")
        out = {"type": "subsurface", "albedo": albedo, "mfp": [max(m, 1e-6) for m in mfp],
               "ior": max(mat["ior"], 1.0001), "roughness": mat["roughness"]}
        for k in ("normal_map", "normal_map_strength", "bump_map", "bump_scale"):
            if k in mat:
                out[k] = mat[k]
        return out

    def _glossy(self, where, node):
        colour = self._param(where, node.inputs["Color"], [0.8, 0.8, 0.8])
        roughness = self._param(where, node.inputs["Roughness"], 0.5)
        dist = getattr(node, "distribution", "GGX")
        if node.bl_idname == "ShaderNodeBsdfAnisotropic" or abs(_value(node.inputs.get("Anisotropy"), 0.0)) > 0:
            self.report.add(where, "anisotropic glossy: isotropic roughness used")
        if dist not in ("GGX", "BECKMANN", "MULTI_GGX", "SHARP"):
            self.report.add(where, f"glossy distribution {dist}: GGX used")
        if isinstance(colour, list) and min(colour) >= 0.999:
            mat = {"type": "conductor", "roughness": 0.0 if dist == "SHARP" else roughness}
            if dist == "BECKMANN":
                mat["distribution"] = "beckmann"
            if dist == "MULTI_GGX":
                mat["multiscatter"] = "compensated"
            return mat
        # A tinted glossy: Cycles' Fresnel is the colour at every angle; kozu's metallic standard reflects the colour
        # at normal incidence and rises to white at grazing (Schlick), and compensates multiple scattering.
        self.report.add(where, "tinted Glossy BSDF as a metallic standard (its colour at normal incidence)")
        return {"type": "standard", "metallic": 1.0, "base_color": colour,
                "roughness": 0.0 if dist == "SHARP" else roughness}

    def _glass(self, where, node):
        colour = self._param(where, node.inputs["Color"], [1.0, 1.0, 1.0])
        roughness = self._param(where, node.inputs["Roughness"], 0.0)
        ior = max(_value(node.inputs["IOR"], 1.45), 1.0001)
        if isinstance(colour, list) and min(colour) >= 0.999:
            mat = {"type": "dielectric", "ior": ior}
            if isinstance(roughness, dict) or roughness > 0.0:
                mat["roughness"] = roughness
            return mat
        return {"type": "standard", "transmission": 1.0, "base_color": colour, "roughness": roughness,
                "ior": min(ior, 3.0)}

    # --- volumes --------------------------------------------------------------------------------------------

    def volume_coefficients(self, where, node):
        """(sigma_t rgb, albedo rgb, g) per unit density factor for a volume shader node, or None."""
        kind = node.bl_idname
        if kind == "ShaderNodeVolumePrincipled":
            for name in ("Emission Strength", "Blackbody Intensity"):
                if _value(node.inputs.get(name), 0.0) > 0.0:
                    self.report.add(where, f"Principled Volume {name}: kozu media do not emit")
            if node.inputs["Color"].is_linked or node.inputs["Density"].is_linked:
                self.report.add(where, "Principled Volume colour or density driven by nodes: unlinked values used")
            st, al = mapping.volume_coefficients(_value(node.inputs["Density"], 1.0), _value(node.inputs["Color"]),
                                                 _value(node.inputs["Absorption Color"], [0.0, 0.0, 0.0]))
            return st, al, _value(node.inputs["Anisotropy"], 0.0)
        if kind == "ShaderNodeVolumeScatter":
            d = _value(node.inputs["Density"], 1.0)
            ss = [d * max(c, 0.0) for c in _value(node.inputs["Color"])]
            return ss, [1.0 if s > 0 else 0.0 for s in ss], _value(node.inputs["Anisotropy"], 0.0)
        if kind == "ShaderNodeVolumeAbsorption":
            d = _value(node.inputs["Density"], 1.0)
            return [d * max(1.0 - c, 0.0) for c in _value(node.inputs["Color"])], [0.0, 0.0, 0.0], 0.0
        if kind == "ShaderNodeAddShader":
            parts = [self.volume_coefficients(where, n) for n in (_linked(s)[0] for s in node.inputs) if n]
            parts = [p for p in parts if p is not None]
            if not parts:
                return None
            st = [sum(p[0][i] for p in parts) for i in range(3)]
            ss = [sum(p[0][i] * p[1][i] for p in parts) for i in range(3)]
            gs = [p[2] for p in parts if max(p[0][i] * p[1][i] for i in range(3)) > 0.0]
            if len(set(gs)) > 1:
                self.report.add(where, "two scattering volumes of different anisotropy: the first one's used")
            return st, [ss[i] / st[i] if st[i] > 0 else 0.0 for i in range(3)], (gs[0] if gs else 0.0)
        self.report.add(where, f"volume shader '{node.name}' ({kind}) not mapped: no medium")
        return None

    def medium(self, where, node):
        coeffs = self.volume_coefficients(where, node)
        if coeffs is None:
            return None
        st, al, g = coeffs
        medium = {"type": "homogeneous", "density": st, "albedo": [min(max(a, 0.0), 1.0) for a in al]}
        if abs(g) > 1e-6:
            medium["phase"] = {"type": "hg", "g": min(max(g, -0.99), 0.99)}
        return medium


class ImageExporter:
    """Image files for textures: an image on disk is referenced where it is (relative to the scene when possible);
    packed and generated images are written once into the scene's `textures/` folder."""

    def __init__(self, folder, report):
        self.folder = folder
        self.report = report
        self.done = {}

    def path(self, image, where):
        import bpy
        key = image.name_full
        if key in self.done:
            return self.done[key]
        path = None
        src = bpy.path.abspath(image.filepath_raw or image.filepath, library=image.library) if image.filepath else ""
        if image.packed_file is not None:
            ext = os.path.splitext(src or image.name)[1] or ".png"
            path = self._unique(mapping.sanitize_name(os.path.splitext(image.name)[0]) + ext)
            with open(path, "wb") as f:
                f.write(image.packed_file.data)
        elif image.source == "FILE" and src and os.path.isfile(src):
            path = os.path.normpath(src)
        elif image.source in ("GENERATED", "FILE") and image.has_data:
            ext, fmt = (".exr", "OPEN_EXR") if image.is_float else (".png", "PNG")
            path = self._unique(mapping.sanitize_name(image.name) + ext)
            copy = image.copy()
            try:
                copy.filepath_raw = path
                copy.file_format = fmt
                copy.save()
            finally:
                bpy.data.images.remove(copy)
        else:
            self.report.add(where, f"image '{image.name}' ({image.source}) has no pixels kozu can read: dropped")
        self.done[key] = path
        return path

    def _unique(self, name):
        os.makedirs(self.folder, exist_ok=True)
        base, ext = os.path.splitext(name)
        path, i = os.path.join(self.folder, name), 1
        while os.path.exists(path):
            path, i = os.path.join(self.folder, f"{base}.{i}{ext}"), i + 1
        return path

    def texture(self, image, where):
        path = self.path(image, where)
        if path is None:
            return None
        cs, exact = mapping.texture_colorspace(image.colorspace_settings.name, image.is_float)
        if not exact:
            self.report.add(where, f"image '{image.name}' in colour space '{image.colorspace_settings.name}': "
                                   "read as linear Rec. 709")
        return {"type": "image", "file": path, "colorspace": cs}
