"""ctest's entry for one Blender comparison scene (label `blender`):
    python3 run_blender_test.py SCENE WORK_DIR KOZU
Runs run_scene.py inside Blender (SCENE `export`: check_export.py, the exporter's JSON without rendering) (`blender` on PATH, or $BLENDER); without Blender it says so and exits 77, which
ctest reports as skipped. scripts/install-deps.sh --tests installs Blender (Debian's, 3.4).
"""
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    if len(sys.argv) != 4:
        sys.exit(f"usage: {sys.argv[0]} SCENE WORK_DIR KOZU")
    scene, work, kozu = sys.argv[1:]
    blender = os.environ.get("BLENDER") or shutil.which("blender")
    if not blender:
        print(f"skipped: blender is not installed, so the add-on's scene '{scene}' is not compared with Cycles "
              "(scripts/install-deps.sh --tests installs it)")
        return 77
    out = os.path.join(work, scene)
    if scene == "export":
        cmd = [blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python",
               os.path.join(HERE, "check_export.py"), "--", out]
    else:
        cmd = [blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python",
               os.path.join(HERE, "run_scene.py"), "--", scene, out, kozu]
    # Blender runs its own Python (Debian's, with its numpy): keep another interpreter's settings out of its way (a
    # pyenv python that runs this script puts its own prefix first on PATH, where Blender would take its modules).
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "PYENV", "VIRTUAL_ENV"))}
    env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep)
                                  if p and os.path.dirname(sys.executable) != p and ".pyenv" not in p)
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, timeout=600)
    # Blender prints a line per render tile and sample; keep what tells the story.
    for line in proc.stdout.splitlines():
        if not line.startswith(("Fra:", "Saved:", " Time:")) and line.strip():
            print(line)
    return proc.returncode


if __name__ == "__main__":
    sys.exit(main())
