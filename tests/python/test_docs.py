"""The examples of docs/python.md run as written.

Every ```python block of the document is executed in order, in one namespace, from a scratch folder that looks
like the repository's root (the paths in the examples are relative to it: scenes/ and tests/ link to the
repository's, out/ is the scratch folder's own). To keep CI short, kozu.render is wrapped to render at most 4 samples
of at most 64 x 48 pixels (the calls, their arguments and what they return are otherwise the document's), and
matplotlib and tqdm, which kozu does not depend on, are replaced by stand-ins that accept any call.
"""
import os
import re
import shutil
import sys
import tempfile
import unittest
from unittest import mock

import kozu

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.environ.get("KOZU_SOURCE_DIR", os.path.join(HERE, "..", ".."))


def python_blocks(markdown):
    return re.findall(r"```python\n(.*?)```", markdown, flags=re.S)


class DocsExamples(unittest.TestCase):
    def test_every_python_block_runs(self):
        with open(os.path.join(SOURCE, "docs", "python.md")) as f:
            blocks = python_blocks(f.read())
        self.assertGreaterEqual(len(blocks), 8)
        real_render = kozu.render
        calls = []

        def small_render(scene, **kw):
            kw["spp"] = min(kw.get("spp") or 4, 4)
            kw.pop("time_limit", None)
            kw["resolution"] = (64, 48)
            calls.append(kw)
            return real_render(scene, **kw)

        stand_in = mock.MagicMock()
        stand_in.subplots.side_effect = lambda n=1, m=1, **_: (mock.MagicMock(), [mock.MagicMock()] * max(n * m, 1))
        matplotlib = mock.MagicMock(pyplot=stand_in)  # `import matplotlib.pyplot as plt` takes the attribute
        modules = {"matplotlib": matplotlib, "matplotlib.pyplot": stand_in, "tqdm": mock.MagicMock()}
        cwd = os.getcwd()
        scratch = tempfile.mkdtemp(prefix="kozu-docs-")
        for name in ("scenes", "tests"):
            os.symlink(os.path.join(os.path.abspath(SOURCE), name), os.path.join(scratch, name))
        os.chdir(scratch)
        try:
            with mock.patch.dict(sys.modules, modules), mock.patch.object(kozu, "render", small_render):
                namespace = {}
                for i, block in enumerate(blocks):
                    with self.subTest(block=i, first_line=block.splitlines()[0]):
                        exec(compile(block, f"docs/python.md block {i}", "exec"), namespace)
        finally:
            os.chdir(cwd)
            shutil.rmtree(scratch, ignore_errors=True)
        self.assertGreaterEqual(len(calls), 5)


if __name__ == "__main__":
    unittest.main()
