"""Only what pyproject.toml cannot say: the wheel carries native libraries (lib/), so it is
tagged for this platform (py3-none-linux_x86_64) and installs into platlib."""
from setuptools import setup
from setuptools.dist import Distribution

try:
    from wheel.bdist_wheel import bdist_wheel

    class PlatformWheel(bdist_wheel):
        def get_tag(self):
            _, _, platform = super().get_tag()
            return "py3", "none", platform

    commands = {"bdist_wheel": PlatformWheel}
except ImportError:  # no wheel package: pip builds through setuptools alone
    commands = {}


class BinaryDistribution(Distribution):
    def has_ext_modules(self):
        return True


setup(distclass=BinaryDistribution, cmdclass=commands)
