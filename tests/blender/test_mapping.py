"""Unit tests of the add-on's conversions that need no Blender (blender/kozu_blender/mapping.py): axes, light units,
colour spaces, cameras, render settings. Run by ctest with any python3:
    python3 -m unittest -v test_mapping        (from tests/blender)
"""
import importlib.util
import math
import os
import random
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
_spec = importlib.util.spec_from_file_location(
    "kozu_blender_mapping", os.path.join(HERE, "..", "..", "blender", "kozu_blender", "mapping.py"))
mapping = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(mapping)


def rotation_z(a):
    c, s = math.cos(a), math.sin(a)
    return [[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]


class Axes(unittest.TestCase):
    def test_blender_up_is_kozu_up(self):
        self.assertEqual(mapping.point([0, 0, 1]), [0, 1, 0])
        # Blender's front view looks along +y; kozu's default camera looks along -z: Blender's +y is kozu's -z.
        self.assertEqual(mapping.point([0, 1, 0]), [0, 0, -1])
        self.assertEqual(mapping.point([1, 0, 0]), [1, 0, 0])

    def test_conversion_is_a_proper_rotation(self):
        m = mapping.BLENDER_TO_KOZU
        det = (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
               + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))
        self.assertEqual(det, 1.0)  # handedness and front sides are kept

    def test_object_matrix_maps_points_like_blender_then_the_axes(self):
        rng = random.Random(1)
        for _ in range(20):
            m = [[rng.uniform(-2, 2) for _ in range(4)] for _ in range(3)] + [[0, 0, 0, 1]]
            p = [rng.uniform(-1, 1) for _ in range(3)]
            want = mapping.point(mapping.transform_point(m, p))
            got = mapping.transform_point(mapping.to_kozu_matrix(m), p)
            for a, b in zip(want, got):
                self.assertAlmostEqual(a, b, places=12)

    def test_rigid_removes_scale_and_keeps_the_view(self):
        m = mapping.matmul(rotation_z(0.7), [[2, 0, 0, 1], [0, 3, 0, 2], [0, 0, 0.5, 3], [0, 0, 0, 1]])
        r = mapping.rigid(m)
        for j in range(3):
            col = [r[i][j] for i in range(3)]
            self.assertAlmostEqual(mapping.dot(col, col), 1.0, places=12)
        look_m = mapping.normalize(mapping.transform_direction(m, [0, 0, -1]))
        look_r = mapping.transform_direction(r, [0, 0, -1])
        for a, b in zip(look_m, look_r):
            self.assertAlmostEqual(a, b, places=12)
        self.assertEqual([r[i][3] for i in range(3)], [m[i][3] for i in range(3)])  # the eye stays


class Lights(unittest.TestCase):
    def test_area_light_radiance_is_power_over_four_areas(self):
        # Cycles 3.4: L = P / (4 A), measured (tests/blender scene light_area), not P / (pi A).
        self.assertEqual(mapping.area_light_radiance(100.0, [1.0, 0.5, 0.0], 2.0), [12.5, 6.25, 0.0])
        with self.assertRaises(ValueError):
            mapping.area_light_radiance(1.0, [1, 1, 1], 0.0)

    def test_point_intensity_and_sphere_radiance_carry_the_same_power(self):
        p, r = 200.0, 0.1
        i = mapping.point_light_intensity(p, [1, 1, 1])[0]
        self.assertAlmostEqual(4 * math.pi * i, p)
        # A sphere of radiance L emits 4 pi r^2 x pi L.
        L = mapping.sphere_light_radiance(p, [1, 1, 1], r)[0]
        self.assertAlmostEqual(4 * math.pi * r * r * math.pi * L, p, places=9)

    def test_spot_angles_reproduce_cycles_smoothing_interval(self):
        size, blend = math.radians(50), 0.3
        cone, falloff = mapping.spot_angles(size, blend)
        self.assertAlmostEqual(cone, 25.0)
        c = math.cos(math.radians(25))
        self.assertAlmostEqual(math.cos(math.radians(falloff)) - c, (1 - c) * blend, places=12)
        self.assertEqual(mapping.spot_angles(size, 0.0), (cone, cone))  # no blend: a hard edge
        self.assertAlmostEqual(mapping.spot_angles(size, 1.0)[1], 0.0, places=6)

    def test_cosine_profile_is_valid_lm63_and_cosine(self):
        lines = mapping.cosine_profile_ies().splitlines()
        self.assertEqual(lines[2], "TILT=NONE")
        header = lines[3].split()
        n_vertical = int(header[3])
        angles = [float(a) for a in lines[5].split()]
        values = [float(v) for v in lines[7].split()]
        self.assertEqual(len(angles), n_vertical)
        self.assertEqual(len(values), n_vertical)
        for a, v in zip(angles, values):
            self.assertAlmostEqual(v, math.cos(math.radians(a)), places=6)

    def test_area_shapes_face_minus_z_and_have_the_right_area(self):
        for verts, area in ((mapping.rectangle(2.0, 0.5), 1.0), (mapping.ellipse_polygon(2.0, 1.0), math.pi / 2)):
            e1 = [verts[1][i] - verts[0][i] for i in range(3)]
            e2 = [verts[2][i] - verts[0][i] for i in range(3)]
            n = mapping.cross(e1, e2)
            self.assertLess(n[2], 0.0)  # kozu's front side is Blender's lit side (-z)
            self.assertAlmostEqual(mapping.polygon_area(verts), area, delta=area * 2e-3)


class Environment(unittest.TestCase):
    @staticmethod
    def cycles_u(d):
        return (0.5 - math.atan2(d[1], d[0]) / (2 * math.pi)) % 1.0

    @staticmethod
    def kozu_u(d_kozu, rotate_deg):
        # kozu looks up the direction turned by -rotate about +y, u = 1/2 + atan2(x, -z) / 2 pi.
        a = -math.radians(rotate_deg)
        x, y, z = d_kozu
        xr, zr = x * math.cos(a) + z * math.sin(a), -x * math.sin(a) + z * math.cos(a)
        return (0.5 + math.atan2(xr, -zr) / (2 * math.pi)) % 1.0

    def test_the_same_direction_reads_the_same_column(self):
        rng = random.Random(2)
        for rho in (0.0, math.radians(40), math.radians(-130)):
            r = mapping.environment_rotate(rho)
            for _ in range(50):
                d = [rng.uniform(-1, 1) for _ in range(3)]
                # Cycles rotates the lookup vector by the Mapping node's rho about z.
                dr = [d[0] * math.cos(rho) - d[1] * math.sin(rho), d[0] * math.sin(rho) + d[1] * math.cos(rho), d[2]]
                du = self.cycles_u(dr) - self.kozu_u(mapping.point(d), r)
                self.assertAlmostEqual(min(abs(du), 1 - abs(du)), 0.0, places=9)


class Camera(unittest.TestCase):
    def test_vertical_fov_from_focal_length(self):
        # 50 mm on a 36 mm sensor fitted to the width of a 16:9 image.
        h = 2 * math.atan(18 / 50)
        want = math.degrees(2 * math.atan(math.tan(h / 2) * 9 / 16))
        self.assertAlmostEqual(mapping.vertical_fov(50, 36, 24, "AUTO", 1920, 1080), want)
        # A portrait image: AUTO fits the sensor width to the height.
        self.assertAlmostEqual(mapping.vertical_fov(50, 36, 24, "AUTO", 1080, 1920), math.degrees(h))
        self.assertAlmostEqual(mapping.vertical_fov(50, 36, 24, "VERTICAL", 1920, 1080),
                               math.degrees(2 * math.atan(12 / 50)))
        self.assertAlmostEqual(mapping.vertical_fov(50, 36, 24, "HORIZONTAL", 1080, 1920),
                               math.degrees(2 * math.atan(math.tan(h / 2) * 1920 / 1080)))

    def test_orthographic_height(self):
        self.assertAlmostEqual(mapping.orthographic_height(8.0, "AUTO", 1600, 800), 4.0)
        self.assertAlmostEqual(mapping.orthographic_height(8.0, "AUTO", 800, 1600), 8.0)

    def test_aperture_radius_is_focal_length_over_twice_the_f_number(self):
        self.assertAlmostEqual(mapping.aperture_radius(50, 2.0), 0.0125)

    def test_resolution_percentage(self):
        self.assertEqual(mapping.render_resolution(1920, 1080, 50), (960, 540))
        self.assertEqual(mapping.render_resolution(3, 3, 10), (1, 1))


class Settings(unittest.TestCase):
    def test_bounces(self):
        self.assertEqual(mapping.max_depth(0), 1)  # direct light only in both
        self.assertEqual(mapping.max_depth(12), 13)
        self.assertEqual(mapping.max_depth(5000), 1024)

    def test_filters_and_tonemaps(self):
        self.assertEqual(mapping.pixel_filter("BLACKMAN_HARRIS", 1.5), ("gaussian", True))
        self.assertEqual(mapping.pixel_filter("BOX", 1.0), ("box", True))
        self.assertEqual(mapping.pixel_filter("GAUSSIAN", 3.0), ("gaussian", False))
        self.assertEqual(mapping.tonemap("Standard"), ("clamp", True))
        self.assertEqual(mapping.tonemap("Filmic"), ("agx", False))
        self.assertEqual(mapping.tonemap("AgX"), ("agx", True))


class Colour(unittest.TestCase):
    def test_colour_spaces(self):
        self.assertEqual(mapping.texture_colorspace("sRGB", False), ("srgb", True))
        self.assertEqual(mapping.texture_colorspace("Non-Color", False), ("linear", True))
        self.assertEqual(mapping.texture_colorspace("Linear", True), ("linear", True))
        # Blender reads float images as linear whatever their setting says.
        self.assertEqual(mapping.texture_colorspace("sRGB", True), ("linear", True))
        self.assertEqual(mapping.texture_colorspace("ACEScg", False), ("linear", False))


class Materials(unittest.TestCase):
    def test_specular_half_is_ior_one_and_a_half(self):
        self.assertAlmostEqual(mapping.ior_from_specular(0.5), 1.5, places=12)
        f0 = ((mapping.ior_from_specular(0.8) - 1) / (mapping.ior_from_specular(0.8) + 1)) ** 2
        self.assertAlmostEqual(f0, 0.064, places=12)
        self.assertEqual(mapping.ior_from_specular(0.0), 1.0)

    def test_principled_volume_coefficients(self):
        st, al = mapping.volume_coefficients(2.0, [0.8, 0.5, 0.0])
        self.assertEqual(st, [2.0, 2.0, 2.0])  # absorption colour black: extinction = density
        for a, want in zip(al, [0.8, 0.5, 0.0]):
            self.assertAlmostEqual(a, want)
        st, al = mapping.volume_coefficients(1.0, [0.5, 0.5, 0.5], [1.0, 1.0, 1.0])
        self.assertEqual(st, [0.5, 0.5, 0.5])  # absorption colour white: no absorption
        self.assertEqual(al, [1.0, 1.0, 1.0])

    def test_names(self):
        self.assertEqual(mapping.sanitize_name("Suzanne/01 ü"), "Suzanne_01__")
        self.assertEqual(mapping.sanitize_name(".."), "unnamed")


if __name__ == "__main__":
    unittest.main()
