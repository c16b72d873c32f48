"""Run the add-on's Blender tests: pytest inside this one Blender process.

    blender --background --factory-startup -noaudio --python-exit-code 1 \
        --python tests/blender/run.py -- --zip build/blender_addon/particlemesh-*.zip \
        [--data ../shared/data] [pytest arguments, e.g. -k bake -x]

The zip is installed with preferences.addon_install into a temporary BLENDER_USER_SCRIPTS
(conftest.py), so the test sees exactly what a user installs. Exits non-zero if any test
fails."""
import argparse
import os
import sys

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
parser = argparse.ArgumentParser(prog="run.py")
parser.add_argument("--zip", required=True, help="the add-on zip built by particlemesh_addon_zip")
parser.add_argument("--data", help="the shared test data folder (default: $PM_TEST_DATA)")
args, pytest_args = parser.parse_known_args(argv)

os.environ["PM_ADDON_ZIP"] = os.path.abspath(args.zip)
if args.data:
    os.environ["PM_TEST_DATA"] = os.path.abspath(args.data)
# The add-on must load the library it carries in its zip, not one named by the environment.
os.environ.pop("PARTICLEMESH_LIBRARY", None)
os.environ.pop("PARTICLEMESH_PCL_LIBRARY", None)

import pytest  # noqa: E402  (Debian's python3-pytest; Blender 3.4 runs the system Python)

here = os.path.dirname(os.path.abspath(__file__))
code = pytest.main([here, "-p", "no:cacheprovider", "-q", "-rsx", *pytest_args])
print(f"particlemesh Blender tests: pytest exit code {int(code)}", flush=True)
if code != 0:
    sys.stdout.flush()
    sys.stderr.flush()
    # SystemExit leaves Blender with this status (--python-exit-code covers exceptions only).
    sys.exit(int(code))
