"""The scenes that ship with rtlab: the demo scene (the course's Ex 25) lives here, so that
whatever needs it (the CLI's ``demo`` verb, the benchmarks, the tests) reads it from the
scenes, not from the command line."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

#: The built-in demo scene: the course's Ex 25 (three reflective spheres, two lights, a floor).
DEMO_SCENE = "ex25.toml"


def demo_scene_path() -> Path:
    """The installed demo scene's file (inside the package, wherever it is installed)."""
    return Path(str(resources.files(__name__) / DEMO_SCENE))
