"""The one error type users see: which file, which field, which rule."""

from __future__ import annotations


class SnnccError(Exception):
    """A user-facing error rendered as one line: ``file: field: rule``.

    ``file`` is the input or output concerned (may be None), ``field`` the part of it that is
    wrong (a key, a node, a dataset path), ``rule`` what was expected.
    """

    def __init__(self, rule: str, *, file: str | None = None, field: str | None = None):
        self.rule = rule
        self.file = None if file is None else str(file)
        self.field = field
        super().__init__(self.line())

    def line(self) -> str:
        parts = [p for p in (self.file, self.field) if p]
        return ": ".join(parts + [self.rule])

    def with_file(self, file: str) -> "SnnccError":
        """The same error, attributed to ``file`` if it names none yet."""
        if self.file is None:
            self.file = str(file)
            self.args = (self.line(),)
        return self
