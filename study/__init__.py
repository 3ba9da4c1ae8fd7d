"""rtlab's numerical stability study (issue 11): families of stiff cases, each with a knob swept
over its range, ground truth from exact and high-precision arithmetic, the methods side by side
(rtlab's robust primitives, the textbook formulas in double and float, Mitsuba, Embree through
embreex), metrics, and the report: ``rtlab study stiff --out DIR``.

Families (study/families.py): sphere-distance, grazing, self-intersection, light-near-surface,
scaling; triangles (far from the origin: rays at the interior, exactly at vertices and edges,
nearly in the plane), slivers (aspect down to 1e-8, and 0: zero-area), mesh-leaks (a closed
icosahedron and cube up to 1e8 away, rays exactly through vertices and edges), boxes (+-0.0
direction components, origins on face planes, rays through edges and corners); and
(study/families_scenes.py) nearly-touching (two spheres, a sphere on a plane, two planes, gaps
down to one ulp: which surface is met first), mirror-chains (8 reflections between them),
grazing-cylinder, far-camera (rtlab's own pixel rays from up to 1e8 away, fields of view down
to 1e-7 degrees) and rotated-boxes (self-intersection under random rotations)."""
