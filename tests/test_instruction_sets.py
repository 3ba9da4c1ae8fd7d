"""The core built for machines without AVX-512 passes the packet tests, bit for bit against the
one-ray code as the native build does. A packet holds as many rays as the widest vector register
holds doubles (power.h rays_per_packet): 8 with AVX-512, 4 with AVX2, 2 with SSE2 alone. The
machines of this project have AVX-512, so without these builds the packets of 4 and of 2 lanes
(and 22_mesh_packets.h's blocks of 4 x 1 and 2 x 1 pixels, pixel_rect()'s corners in groups,
21_wide_bvh.h's fma for a packet's lanes) would never run here. With 8 lanes on AVX2 the
packets were 2.1x slower than the one-ray tracer (power.h says why); the width is checked by
tests/with_core.py before any test runs.

Each build goes to build/avx2 or build/sse2 (-DRTLAB_MARCH=x86-64-v3, x86-64); ninja rebuilds
only what changed."""

import pytest

from reference.bench import cpu
from tests.core_builds import ROOT, build_core, run_tests_with

# The tests whose code differs with the packet's width: packets against one-ray renders of every
# canonical scene of spheres and planes, the packet's power() and ray origins lane by lane, the
# mesh packets and the wide hierarchies (which use the packet's fma).
PACKET_TESTS = (
    "tests/tracer/test_packet.py",
    "tests/tracer/test_mesh_packets.py",
    "tests/tracer/test_wide_bvh.py",
    "tests/tracer/test_wide_bvh8.py",
)


@pytest.mark.parametrize(
    ("march", "build", "flag"), [("x86-64-v3", "avx2", "avx2"), ("x86-64", "sse2", "sse2")]
)
def test_the_core_built_for_an_older_instruction_set_passes_the_packet_tests(march, build, flag):
    assert flag in cpu()["cpu_flags"], f"this machine cannot run a build for {march} (no {flag})"
    so = build_core(ROOT / "build" / build, f"-DRTLAB_MARCH={march}")
    run_tests_with(so, build, *PACKET_TESTS)
