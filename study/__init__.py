"""rtlab's numerical stability study (issue 11): families of stiff cases, each with a knob swept
over its range, ground truth from exact and high-precision arithmetic, the methods side by side
(rtlab's robust primitives, the textbook formulas in double and float, Mitsuba), metrics, and
the report: ``rtlab study stiff --out DIR``."""
