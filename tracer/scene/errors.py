"""The one error a scene can raise: which file, which key, and what was expected."""

from __future__ import annotations


class SceneError(ValueError):
    """A scene that cannot be rendered: says which file, which key, and what was expected."""

    def __init__(self, source: str, key: str, message: str) -> None:
        self.source = source
        self.key = key
        self.message = message
        where = f"{source}: {key}" if key else source
        super().__init__(f"{where}: {message}")
