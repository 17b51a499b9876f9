"""Blender → kozu conversions that need no Blender: axes, units, colour spaces, cameras, render settings.

Everything here is plain Python (lists, math), so tests/blender/test_mapping.py checks it with any python3, and the
exporter (export.py) calls it with values it read from bpy. Each conversion states the convention it bridges; the
light units were measured against Cycles 3.4 (docs/blender.md, "Units"), not taken from its manual.
"""
import math

# --- Axes -------------------------------------------------------------------------------------------------------
# Blender is z-up, kozu y-up (glTF's convention). Blender's (x, y, z) is kozu's (x, z, -y): a rotation of -90 degrees
# about x, proper (determinant +1), so handedness, front sides and right-handed rotations are kept.
BLENDER_TO_KOZU = [[1.0, 0.0, 0.0, 0.0],
                   [0.0, 0.0, 1.0, 0.0],
                   [0.0, -1.0, 0.0, 0.0],
                   [0.0, 0.0, 0.0, 1.0]]


def matmul(a, b):
    """The product of two 4 x 4 matrices given as lists of rows."""
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def to_kozu_matrix(m):
    """A Blender object-to-world matrix (4 rows) as kozu's object-to-world: the same map, in kozu's axes."""
    return matmul(BLENDER_TO_KOZU, [list(map(float, row)) for row in m])


def point(p):
    """A Blender position (or direction) as kozu's: the rotation BLENDER_TO_KOZU, the convention the tests check
    to_kozu_matrix against."""
    return [float(p[0]), float(p[2]), -float(p[1])]


def transform_point(m, p):
    """m (4 rows) applied to the point p."""
    return [m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3] for i in range(3)]


def transform_direction(m, d):
    """m's linear part (3 x 3) applied to the direction d."""
    return [m[i][0] * d[0] + m[i][1] * d[1] + m[i][2] * d[2] for i in range(3)]


def normalize(v):
    n = math.sqrt(sum(c * c for c in v))
    if not n > 0.0:
        raise ValueError("zero-length vector")
    return [c / n for c in v]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def rigid(m):
    """m without its scale and shear: kozu's camera transform takes rotations and translations only, while Blender
    lets a camera object carry any scale (which Blender ignores for the view). Gram-Schmidt on the columns."""
    x = normalize([m[0][0], m[1][0], m[2][0]])
    y = [m[0][1], m[1][1], m[2][1]]
    y = normalize([y[i] - dot(y, x) * x[i] for i in range(3)])
    z = cross(x, y)
    if dot(z, [m[0][2], m[1][2], m[2][2]]) < 0.0:
        z = [-c for c in z]  # a mirrored camera: keep the look direction (-z), lose the mirror
    return [[x[0], y[0], z[0], m[0][3]], [x[1], y[1], z[1], m[1][3]], [x[2], y[2], z[2], m[2][3]],
            [0.0, 0.0, 0.0, 1.0]]


# --- Colour -----------------------------------------------------------------------------------------------------
# Blender's image colour spaces (OpenColorIO names of its default config, 3.x and 4.x) to kozu's texture
# `colorspace`. kozu decodes sRGB or reads linear Rec. 709; anything else is reported and read linear.
_COLORSPACES = {
    "srgb": "srgb",
    "linear": "linear",
    "linear rec.709": "linear",
    "linear rec.709 (srgb)": "linear",
    "scene linear": "linear",
    "non-color": "linear",
    "raw": "linear",
    "xyz": None,
    "filmic log": None,
    "filmic srgb": None,
    "linear aces": None,
    "acescg": None,
    "linear acescg": None,
}


def texture_colorspace(blender_name, is_float):
    """kozu's `colorspace` for an image Blender reads in the colour space `blender_name`, and whether it is exact.

    Blender's "sRGB" on a float image (EXR, HDR) still means linear data in Blender 3.x/4.x (it ignores the
    setting for float buffers), so kozu's "linear" is the match there."""
    key = (blender_name or "").strip().lower()
    cs = _COLORSPACES.get(key, None)
    if cs is None:
        return "linear", False
    if cs == "srgb" and is_float:
        return "linear", True
    return cs, True


def luminance(rgb):
    """Rec. 709 luminance of a linear colour."""
    return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]


# --- Lights -----------------------------------------------------------------------------------------------------
# Measured against Cycles 3.4 (bench/cycles/scenes.py and tests/blender): its watts are not radiometric watts.
#   area lights: radiance L = P / (4 A), not P / (pi A);
#   point and spot lights: intensity I = P / (4 pi) W/sr (a spot keeps the point light's intensity in its cone),
#   and Cycles 3.4's spot lights fall off as cos(theta) about their axis inside the cone (an IES profile in kozu);
#   sun: strength is the irradiance in W/m^2 on a surface facing it; angle is the disk's angular diameter.
#   mesh emission: strength x colour is the radiance.


def area_light_radiance(power, color, area):
    """kozu emission (radiance) of a Blender area light of `power` watts, `color`, and world-space area."""
    if not area > 0.0:
        raise ValueError("area light of zero area")
    return [power * c / (4.0 * area) for c in color]


def point_light_intensity(power, color):
    """kozu intensity (W/sr) of a Blender point or spot light of `power` watts."""
    return [power * c / (4.0 * math.pi) for c in color]


def sphere_light_radiance(power, color, radius):
    """Radiance of a kozu emitting sphere of `radius` that matches a Blender point light of that radius: the
    sphere's intensity pi r^2 L equals the point light's P / (4 pi)."""
    return [i / (math.pi * radius * radius) for i in point_light_intensity(power, color)]


def spot_angles(spot_size, spot_blend):
    """kozu (cone_angle, falloff_angle) in degrees for Blender's spot_size (the full cone, radians) and blend.

    Cycles smooths the edge over cos(angle) in [cos c, cos c + (1 - cos c) blend], c the half-angle; kozu's falloff
    starts at falloff_angle, so that is acos(cos c + (1 - cos c) blend)."""
    half = 0.5 * spot_size
    c = math.cos(half)
    blend = min(max(spot_blend, 0.0), 1.0)
    falloff = math.acos(min(1.0, c + (1.0 - c) * blend))
    cone = min(math.degrees(half), 179.9)
    return cone, min(math.degrees(falloff), cone)


def cosine_profile_ies():
    """An IES LM-63 profile of intensity cos(theta) about the nadir, every degree to 90: Cycles 3.4's spot falloff
    inside the cone, which kozu's spot takes as its `profile`."""
    angles = range(91)
    return ("IESNA:LM-63-2002\n[TEST] kozu_blender: Cycles 3.4's spot falloff cos(theta)\nTILT=NONE\n"
            f"1 -1 1 {len(angles)} 1 1 2 0 0 0\n1 1 0\n"
            + " ".join(str(a) for a in angles) + "\n0\n"
            + " ".join(f"{math.cos(math.radians(a)):.6f}" for a in angles) + "\n")


def ellipse_polygon(size_x, size_y, segments=64):
    """Vertices (local x, y, 0) of a polygon for a disk or ellipse area light, counter-clockwise seen from -z (the
    side Blender's area lights face), so kozu's front side is the lit one."""
    return [[0.5 * size_x * math.cos(-2.0 * math.pi * i / segments), 0.5 * size_y * math.sin(-2.0 * math.pi * i / segments),
             0.0] for i in range(segments)]


def rectangle(size_x, size_y):
    """Quad vertices (local) of a rectangle area light, counter-clockwise seen from -z."""
    hx, hy = 0.5 * size_x, 0.5 * size_y
    return [[-hx, -hy, 0.0], [-hx, hy, 0.0], [hx, hy, 0.0], [hx, -hy, 0.0]]


def polygon_area(vertices):
    """Area of a planar polygon (any orientation) by the vector area formula."""
    s = [0.0, 0.0, 0.0]
    n = len(vertices)
    for i in range(n):
        c = cross(vertices[i], vertices[(i + 1) % n])
        s = [s[k] + c[k] for k in range(3)]
    return 0.5 * math.sqrt(dot(s, s))


# --- Environment ------------------------------------------------------------------------------------------------
# Cycles' equirectangular lookup (z-up): u = 1/2 - phi / 2 pi, phi = atan2(dy, dx). kozu's (y-up): u = 1/2 +
# atan2(x, -z) / 2 pi, which for kozu's (x, y, z) = (dx, dz, -dy) is 3/4 - phi / 2 pi: a quarter turn further.
# kozu's `rotate` r looks the image up at the direction turned by -r about +y (= Blender's +z), which adds r / 2 pi
# to u; so r = -90 degrees undoes the quarter. A Mapping node rotating the lookup vector by rho about z moves
# Cycles' u by -rho / 2 pi, which kozu matches with r = -90 degrees - rho (tests/blender, scene "world_hdr").
ENVIRONMENT_ROTATE_OFFSET = -90.0


def environment_rotate(mapping_z_radians):
    """kozu's environment `rotate` (degrees) for a Mapping node's z rotation (radians) in front of the image."""
    r = ENVIRONMENT_ROTATE_OFFSET - math.degrees(mapping_z_radians)
    return (r + 180.0) % 360.0 - 180.0


# --- Camera -----------------------------------------------------------------------------------------------------

def sensor_fit_axis(sensor_fit, width, height):
    """'x' or 'y': the image axis Blender fits the sensor (or the orthographic scale) to."""
    if sensor_fit == "HORIZONTAL":
        return "x"
    if sensor_fit == "VERTICAL":
        return "y"
    return "x" if width >= height else "y"


def vertical_fov(lens_mm, sensor_width, sensor_height, sensor_fit, width, height):
    """kozu's vertical field of view (degrees) for a Blender perspective camera and render size."""
    axis = sensor_fit_axis(sensor_fit, width, height)
    sensor = sensor_height if sensor_fit == "VERTICAL" else sensor_width
    half = math.atan(0.5 * sensor / lens_mm)
    if axis == "x":
        half = math.atan(math.tan(half) * height / width)
    return math.degrees(2.0 * half)


def orthographic_height(ortho_scale, sensor_fit, width, height):
    """kozu's orthographic `scale` (the image's height) for Blender's ortho_scale (along the fitted axis)."""
    if sensor_fit_axis(sensor_fit, width, height) == "x":
        return ortho_scale * height / width
    return ortho_scale


def aperture_radius(lens_mm, fstop, orthographic=False):
    """The lens radius (scene units, metres) Cycles uses for a Blender camera's f-stop: (focal length) / (2 N)."""
    fstop = max(fstop, 1e-5)
    if orthographic:
        return 1.0 / (2.0 * fstop)
    return lens_mm * 1e-3 / (2.0 * fstop)


def render_resolution(res_x, res_y, percentage):
    """The rendered size: Blender rounds resolution x percentage / 100 down, at least 1."""
    return max(1, int(res_x * percentage / 100)), max(1, int(res_y * percentage / 100))


# --- Render settings --------------------------------------------------------------------------------------------

def max_depth(max_bounces):
    """kozu's max_depth (scattering events on a path) for Cycles' max_bounces (0 = direct light only)."""
    return min(max(int(max_bounces) + 1, 1), 1024)


# Cycles' pixel filter to kozu's: a Blackman-Harris of width 1.5 px (Cycles' default) is closest to kozu's
# Gaussian (sigma 0.5, radius 1.5); a box to a box.
def pixel_filter(filter_type, width):
    if filter_type == "BOX":
        return "box", abs(width - 1.0) < 1e-6
    if filter_type in ("GAUSSIAN", "BLACKMAN_HARRIS"):
        return "gaussian", abs(width - 1.5) < 1e-6
    return "gaussian", False


# Blender's view transforms to kozu's tone maps (for 8-bit outputs): Standard is a plain clamp to sRGB; Filmic and
# AgX compress highlights, which kozu's AgX does in the way closest to both (kozu has no Filmic LUT).
_TONEMAPS = {"Standard": ("clamp", True), "Raw": ("clamp", False), "Filmic": ("agx", False),
             "Filmic Log": ("agx", False), "AgX": ("agx", True), "Khronos PBR Neutral": ("neutral", True),
             "False Color": ("clamp", False)}


def tonemap(view_transform):
    """kozu's `--tonemap` for Blender's view transform, and whether it is the same curve."""
    return _TONEMAPS.get(view_transform, ("agx", False))


# --- Materials --------------------------------------------------------------------------------------------------

def ior_from_specular(specular):
    """The dielectric index whose normal reflectance is the Principled BSDF's (v1, Blender 3.x) F0 = 0.08 specular:
    0.5 is IOR 1.5. kozu's standard takes indices in [1, 3]."""
    f0 = min(max(0.08 * specular, 0.0), 0.999)
    s = math.sqrt(f0)
    return min(max((1.0 + s) / (1.0 - s), 1.0), 3.0)


def volume_coefficients(density, scatter_color, absorption_color=(0.0, 0.0, 0.0)):
    """Principled Volume's (Cycles) scattering and extinction per channel: sigma_s = density colour, sigma_a =
    density (1 - colour)(1 - absorption colour). Returns (sigma_t, albedo) per channel."""
    st, al = [], []
    for c, a in zip(scatter_color, absorption_color):
        c = max(c, 0.0)
        s = density * c
        t = s + density * max(1.0 - c, 0.0) * max(1.0 - a, 0.0)
        st.append(t)
        al.append(min(s / t, 1.0) if t > 0.0 else 0.0)
    return st, al


def sanitize_name(name):
    """A file-system-safe form of a Blender data-block name (for mesh and image files beside the scene)."""
    safe = "".join(ch if (ch.isascii() and ch.isalnum()) or ch in "-_." else "_" for ch in name)
    return safe.strip(".") or "unnamed"
