"""reference/packet_model.py: which packet a pixel's is, the trace as llvm-mca's input, and
llvm-mca's summary read back. (Tracing itself needs gdb and llvm-mca-19, which `make` does
not install: the tool is run by hand, reference/speed-log.md.)"""

from __future__ import annotations

import pytest

from reference.packet_model import (
    listing,
    mnemonic_mix,
    packet_index,
    packet_store,
    parse_addr2line,
    parse_mca,
    source_text,
    step_of,
    tile_side,
    trace_to_asm,
    where_time_goes,
)


def test_tile_side_follows_11_render_h() -> None:
    # 11_render.h: a 64 x 64 image had 16 tiles of 16 x 16 for 2 threads; it gets tiles of 8.
    assert tile_side(64, 64, threads=2) == 8
    assert tile_side(64, 64, threads=1) == 16  # 16 tiles of 16: enough for one thread
    assert tile_side(1920, 1024) == 16


def test_packet_index_counts_tiles_rows_and_packets() -> None:
    # Ex 25 at 1920x1024: tiles of 16 x 16, 120 a row, 2 packets of 8 a tile's row.
    assert packet_index(0, 0, 1920, 1024, 8) == 0
    assert packet_index(8, 0, 1920, 1024, 8) == 1
    assert packet_index(0, 1, 1920, 1024, 8) == 2  # the tile's next row, not the image's
    assert packet_index(16, 0, 1920, 1024, 8) == 32  # the next tile
    assert packet_index(0, 16, 1920, 1024, 8) == 120 * 32  # the next row of tiles
    # The speed log's packets: tile 44 * 120 + 10, its row 1, packet 0.
    assert packet_index(160, 705, 1920, 1024, 8) == (44 * 120 + 10) * 32 + 2
    # Packets of 4 (the AVX2 build): four a tile's row.
    assert packet_index(164, 705, 1920, 1024, 4) == (44 * 120 + 10) * 64 + 4 + 1


def test_packet_index_skips_the_tiles_filled_without_a_ray() -> None:
    # Ex 25 at 1920x1024: the core fills the sky's tiles with the background (12_packet.h
    # sky_only()), and they hold no packet. Here the first row of tiles, and one tile more.
    def filled(x0: int, y0: int, x1: int, y1: int) -> bool:
        assert (x1 - x0, y1 - y0) == (16, 16)
        return y0 == 0 or (x0, y0) == (16, 16)

    assert packet_index(0, 16, 1920, 1024, 8, filled) == 0
    assert packet_index(32, 17, 1920, 1024, 8, filled) == 32 + 2
    with pytest.raises(ValueError, match=r"pixel \(20, 20\) lies in a tile filled"):
        packet_index(20, 20, 1920, 1024, 8, filled)


def test_the_cores_filled_tiles_are_ex25s_sky() -> None:
    """The core's answer that packet_model counts by: Ex 25's top left tile is sky, its bottom
    left floor, and the tile holding the green sphere's top (over the horizon) is traced."""
    from reference.bench import ex25_scene
    from tracer import _core
    from tracer.render import to_core

    core = to_core(ex25_scene(1920, 1024))
    assert _core.tile_filled(core, 0, 0, 16, 16)
    assert not _core.tile_filled(core, 0, 1008, 16, 1024)
    top = [y for y in range(0, 1024, 16) if not _core.tile_filled(core, 960, y, 976, y + 16)]
    assert top[0] < 256  # the horizon's tiles begin at row 256; the sphere rises above it
    assert sum(_core.tile_filled(core, 0, y, 16, y + 16) for y in range(0, 1024, 16)) == 16


def test_packet_index_at_ragged_edges() -> None:
    # 20 x 12: tiles of 8 (its 2 tiles of 16 are fewer than 16), 3 across (8, 8, 4 wide), 2 down
    # (8, 4 high); one packet of 8 per tile row, the last tile's 4 wide.
    assert packet_index(17, 3, 20, 12, 8) == 8 + 8 + 3
    assert packet_index(19, 11, 20, 12, 8) == 24 + 4 + 4 + 3
    with pytest.raises(ValueError, match=r"pixel \(20, 0\) is outside the 20x12 image"):
        packet_index(20, 0, 20, 12, 8)


def test_trace_to_asm_aims_jumps_at_one_label_and_drops_gdb_annotations() -> None:
    trace = [
        "2709a\tvmovaps 0x387fe(%rip),%ymm5        # 0x7ffff73308a0",
        "27127\tjge    0x7ffff72fb2a0 <_ZN2rt19render_tile_packetsERKNS_13PacketCullingE+14960>",
        "27130\tcall   0x7ffff72f0000 <_ZN2rt5powerEDv8_dS0_>",
        "#packet",
        "27135\tvmulpd %zmm1,%zmm2,%zmm3",
    ]
    assert trace_to_asm(trace) == (
        ".Ltrace:\n  vmovaps 0x387fe(%rip),%ymm5\n  jge .Ltrace\n  vmulpd %zmm1,%zmm2,%zmm3\n"
    )


# llvm-mca-19 -mcpu=rocketlake -iterations=100 -bottleneck-analysis -instruction-info=false
# -resource-pressure=false on two multiplies, two adds, a division and a loop's count (its
# output, cut after the part read, a trailing space taken off).
MCA_OUTPUT = """Iterations:        100
Instructions:      700
Total Cycles:      1614
Total uOps:        900

Dispatch Width:    6
uOps Per Cycle:    0.56
IPC:               0.43
Block RThroughput: 16.0


Cycles with backend pressure increase [ 19.14% ]
Throughput Bottlenecks:
  Resource Pressure       [ 19.14% ]
  - ICXFPDivider  [ 18.90% ]
  - ICXPort0  [ 16.23% ]
  - ICXPort5  [ 1.98% ]
  Data Dependencies:      [ 3.47% ]
  - Register Dependencies [ 3.47% ]
  - Memory Dependencies   [ 0.00% ]

Critical sequence based on the simulation:
"""


def test_parse_mca_reads_totals_and_resources() -> None:
    m = parse_mca("rocketlake", MCA_OUTPUT)
    assert (m.instructions, m.cycles, m.iterations) == (700, 1614, 100)
    assert m.per_iteration() == pytest.approx(16.14)
    assert m.bottlenecks == {"ICXFPDivider": 18.90, "ICXPort0": 16.23, "ICXPort5": 1.98}


def test_parse_mca_without_bottlenecks_and_without_totals() -> None:
    quiet = MCA_OUTPUT.split("Cycles with")[0] + "No resource or data dependency bottlenecks"
    assert parse_mca("znver4", quiet).bottlenecks == {}
    from reference.packet_model import ModelError

    with pytest.raises(ModelError, match="llvm-mca for znver4 printed no 'Total Cycles'"):
        parse_mca("znver4", "Iterations: 1\nInstructions: 2\n")


# objdump's listing of render_tile_packets() in a -march=rocketlake build (lines of it), and
# the source lines its line tables give for the conversions: a lone conversion of another
# path comes first, then a whole packet's three, interleaved with a move.
LISTING = """
   26352:\tvcvtpd2ps %xmm9,%xmm9
   2650f:\tvcvtpd2ps %zmm9,%ymm9
   26515:\tvpermps %ymm9,%ymm5,%ymm10
   268c2:\tdata16 data16 data16 data16 cs nopw 0x0(%rax,%rax,1)
   268d0:\tvcvtpd2ps %zmm7,%ymm0
   268d6:\tvmovaps 0x39462(%rip),%ymm4
   268de:\tvcvtpd2ps %zmm1,%ymm1
   268e4:\tvcvtpd2ps %zmm4,%ymm2
"""
SOURCE = {
    0x26352: "    px[0] = float(color.r), px[1] = float(color.g), px[2] = float(color.b);",
    0x2650F: "    px[0] = float(color.r), px[1] = float(color.g), px[2] = float(color.b);",
    0x268D0: "        const FloatLanes r = __builtin_convertvector(c.r, FloatLanes),",
    0x268DE: "                         g = __builtin_convertvector(c.g, FloatLanes),",
    0x268E4: "                         b = __builtin_convertvector(c.b, FloatLanes);",
}


def test_packet_store_is_store_pixels_conversion_of_the_widest_vectors() -> None:
    assert packet_store(LISTING, SOURCE.__getitem__) == 0x268D0
    # An AVX2 build's conversions are of 256-bit vectors.
    assert packet_store(LISTING.replace("%zmm", "%ymm"), SOURCE.__getitem__) == 0x268D0
    # Without line tables (every source line unknown) there is none to stop at.
    assert packet_store(LISTING, lambda address: "") is None
    # The colour read from the stack (a core of 2026-12-06): a 512-bit source, by its
    # destination; objdump's suffix names the width of a memory source into an xmm register.
    spilled = LISTING.replace("vcvtpd2ps %zmm7,%ymm0", "vcvtpd2ps 0x540(%rsp),%ymm0")
    assert packet_store(spilled, SOURCE.__getitem__) == 0x268D0
    narrow = LISTING.replace("vcvtpd2ps %zmm7,%ymm0", "vcvtpd2psy 0x540(%rsp),%xmm0")
    narrow = narrow.replace("%zmm", "%ymm")
    assert packet_store(narrow, SOURCE.__getitem__) == 0x268D0


# addr2line -a -f -i -C on two instructions of a Clang 19 RelWithDebInfo core (argument lists
# cut short): one in render_tile_packets() itself, one in sphere_t() inlined through
# closest_hit(), trace_level() and trace().
ADDR2LINE = """0x0000000000026f35
rt::render_tile_packets(rt::PacketCulling const&, ...)
/home/me/rtlab/tracer/cpp/12_packet.h:142
0x0000000000027733
rt::sphere_t(rt::Sphere const&, rt::RayL const&, ...)
/home/me/rtlab/tracer/cpp/12_packet.h:146
rt::closest_hit(rt::Scene const&, rt::RayL const&, ...)
/home/me/rtlab/tracer/cpp/12_packet.h:510 (discriminator 1)
rt::trace_level(rt::Scene const&, rt::RayL&, ...)
/home/me/rtlab/tracer/cpp/12_packet.h:777
rt::trace(rt::Scene const&, rt::RayL, ...)
/home/me/rtlab/tracer/cpp/12_packet.h:896
rt::render_tile_packets(rt::PacketCulling const&, ...)
/home/me/rtlab/tracer/cpp/12_packet.h:1013
"""


def test_parse_addr2line_keeps_each_address_inlining_chain() -> None:
    places = parse_addr2line(ADDR2LINE)
    here = "/home/me/rtlab/tracer/cpp/12_packet.h"
    assert places[0x26F35] == [("render_tile_packets", f"{here}:142")]
    chain = places[0x27733]
    assert [f for f, _ in chain] == [
        "sphere_t", "closest_hit", "trace_level", "trace", "render_tile_packets",
    ]  # fmt: skip
    assert chain[1] == ("closest_hit", f"{here}:510")  # the discriminator dropped
    # The step: the line of trace_level() the instruction was inlined from, not the innermost
    # function's; outside trace_level() and trace(), render_tile_packets()'s own line.
    assert step_of(chain) == f"{here}:777 trace_level"
    assert step_of(places[0x26F35]) == f"{here}:142 render_tile_packets"
    assert step_of([]) == "?"


def test_where_time_goes_counts_instructions_and_vector_arithmetic_per_step() -> None:
    places = parse_addr2line(ADDR2LINE)
    trace = [
        "27733\tvmulpd %zmm1,%zmm2,%zmm3",
        "27733\tvmulpd %zmm1,%zmm2,%zmm3",  # executed twice
        "26f35\tvmovapd %zmm1,(%rsp)",
        "#packet",
        "99999\tnop",  # no line tables for it
    ]
    text = where_time_goes(
        trace, places, top=5, source=lambda step: "HERE" if "777" in step else ""
    )
    lines = text.splitlines()
    step_rows = lines[1 : lines.index(next(x for x in lines[1:] if "function" in x))]
    assert step_rows[0].split() == ["2", "50%", "2", "12_packet.h:777", "trace_level", "HERE"]
    assert ["1", "25%", "0", "12_packet.h:142", "render_tile_packets"] in [
        r.split() for r in step_rows
    ]
    assert ["1", "25%", "0", "?"] in [r.split() for r in step_rows]
    assert "sphere_t" in text.split("function")[1]  # the innermost function's table


def test_listing_names_each_instructions_function_line_and_step() -> None:
    places = parse_addr2line(ADDR2LINE)
    packets = [
        ["27733\tvmulpd %zmm1,%zmm2,%zmm3", "26f35\tvmovapd %zmm1,(%rsp)"],
        ["99999\tnop", "#packet"],  # no line tables for it; a marker is not an instruction
    ]
    rows = listing(packets, places).splitlines()
    assert rows[0] == "# packet 0" and rows[3] == "# packet 1" and len(rows) == 5
    assert rows[1].split() == [
        "vmulpd",
        "%zmm1,%zmm2,%zmm3",
        "sphere_t",
        "12_packet.h:146",
        "12_packet.h:777",
        "trace_level",
    ]  # the innermost function and line, then the step
    assert rows[2].split()[-2:] == ["12_packet.h:142", "render_tile_packets"]
    assert rows[4].split() == ["nop", "?", "?"]


def test_source_text_reads_the_line_at_a_place(tmp_path) -> None:
    header = tmp_path / "a.h"
    header.write_text("one\n    two;  \n")
    assert source_text(f"{header}:2 trace_level") == "two;"  # a step's function ignored
    assert source_text(f"{header}:1") == "one"
    assert source_text(f"{header}:3") == "" and source_text(f"{header}:?") == ""
    assert source_text(f"{tmp_path / 'missing.h'}:1") == ""


def test_mnemonic_mix_counts_per_packet_wide_registers_and_stack_operands() -> None:
    trace = [
        "27733\tvmulpd %zmm1,%zmm2,%zmm3",
        "27733\tvmulpd %ymm1,%ymm2,%ymm3",  # not a 512-bit register
        "26f35\tvmovapd %zmm1,0x40(%rsp)",  # a spill
        "#packet",
        "26f40\tvmovapd -0x80(%rbp),%zmm4",  # a reload through the frame pointer
        "26f45\tmov (%rax),%rcx",  # memory, not the stack
        "26f48\tvaddpd 0x10(%rsp,%rax,8),%zmm1,%zmm2",  # indexed from the stack
    ]
    rows = [r.split() for r in mnemonic_mix(trace, packets=2, top=2).splitlines()]
    assert rows[0] == ["a", "packet", "on", "zmm", "mnemonic"]
    assert ["1.0", "0.5", "vmulpd"] in rows[1:3] and ["1.0", "1.0", "vmovapd"] in rows[1:3]
    assert len(rows) == 4  # top 2, then the stack
    assert rows[3][0] == "1.5" and "stack" in rows[3]
