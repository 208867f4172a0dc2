"""Assignment to public attributes a class does not have is refused.

Python stores ``sim.gravty = (0, 0, -1.62)`` (misspelt) or ``sim.friction = 0.3`` (a setting
of the contact law, not of the simulation) as a new attribute that nothing reads: the run
goes on with the old value and no word. The package's top-level objects refuse it instead.
Subclasses written outside the package keep Python's usual freedom.
"""

from __future__ import annotations

from typing import Any


class StrictAttributes:
    """Mixin: after ``_freeze_attributes()``, setting a public name that is neither a class
    attribute (a property, a method) nor an instance attribute set during construction raises
    AttributeError naming the settable properties."""

    _attributes_frozen = False
    # Set at construction and read by the core only then: a new value would change nothing.
    _fixed_after_construction: tuple[str, ...] = ()

    def _freeze_attributes(self) -> None:
        object.__setattr__(self, "_attributes_frozen", True)

    def __setattr__(self, name: str, value: Any) -> None:
        cls = type(self)
        if self._attributes_frozen and name in self._fixed_after_construction:
            raise AttributeError(
                f"{cls.__name__}.{name} is fixed at construction (the core took it then; a new "
                f"value would change nothing): build a new {cls.__name__}, got {value!r}"
            )
        if (
            self._attributes_frozen
            and not name.startswith("_")
            and cls.__module__.startswith("grainscale.")
            and not hasattr(cls, name)
            and name not in self.__dict__
        ):
            settable = sorted(
                [n for n in dir(cls) if isinstance(getattr(cls, n, None), property)]
                + [n for n in self.__dict__ if not n.startswith("_")]
            )
            settable = [
                n
                for n in settable
                if (n in self.__dict__ and n not in self._fixed_after_construction)
                or (n not in self.__dict__ and getattr(cls, n).fset is not None)
            ]
            raise AttributeError(
                f"{cls.__name__} has no attribute {name!r} to set (a misspelt name would be "
                f"ignored silently); settable: {', '.join(settable)}"
            )
        object.__setattr__(self, name, value)
