"""Detail and note texts that carry numbers measured off the clock.

"got MISSION_REQUEST_INT after 0.253 s" would make two runs of the same target differ in
their run.json. A `Measured` text reads the same everywhere a person or an expectations
file sees it (its str: the console line, the `observed` patterns), but also keeps its
`stable` form, with `<name>` where each measured number goes, and the numbers apart in
`values`. The run document stores the stable form and moves the numbers into its
volatile section (conformance/document.py); the reports put them back.
"""

from __future__ import annotations


class Measured(str):
    """`template` with each `<name>` replaced by `values[name]` (numbers already formatted)."""

    stable: str
    values: dict[str, str]

    def __new__(cls, template: str, **values: str) -> "Measured":
        text = template
        for name, value in values.items():
            text = text.replace(f"<{name}>", value)
        self = super().__new__(cls, text)
        self.stable = template
        self.values = dict(values)
        return self

    def __reduce__(self):   # pickles (and copies) as what it is, not as a plain str
        return (_rebuild, (self.stable, self.values))


def _rebuild(stable: str, values: dict[str, str]) -> Measured:
    return Measured(stable, **values)

