"""Where a core's time goes in Ex 25's packets, by a model of the processor (issue 12).

``python -m reference.packet_model [--so CORE.so] [--pixel X Y] [--packets N] [--cpu NAME...]
[--where N] [--mnemonics N]``

There are no hardware counters on these machines, so this steps through the packet tracer
instruction by instruction instead: gdb runs Ex 25 (1920x1024, 1 spp, one thread) in the core
as ``make`` builds it but with its symbols (core_with_symbols()) or the one ``--so`` names,
stops at the pixel store of the packet before the one holding pixel (X, Y), and single-steps
through the next N packets, each from one pixel store to the next. The instructions executed,
in their order, branches pointed at one label, are then handed to LLVM's machine code analyser
(``llvm-mca-19 -mcpu=NAME``), which times them on its model of that processor as if every
branch were foreseen: cycles a packet, instructions a cycle, and the resources that hold it
back. Its first use: why the Intel Xeon of this machine class gives rtlab lower ratios than the
Zen 4 (reference/speed-log.md). That Xeon reports family 6, model 167 (Rocket Lake), but its
flags (AMX, AVX512-FP16) and caches say Sapphire Rapids or later (reference.bench.cpu_core()):
model it as ``sapphirerapids``: 389 cycles for a floor packet by that model, 582 by
``rocketlake``'s (one port for 512-bit adds and multiplies, not two), against some 400 measured
(Ex 25 without its spheres 21.2 ms, without any object 1.4 ms: 19.8 ms at 3.7 GHz over its
181,920 floor packets). ``rocketlake``
was the default until 2026-12-06, and the speed log's Xeon figures before then are its. The
model counts issue
ports and dependences, not the stack's traffic nor mispredictions: it says where a core's time
goes, not which of two builds a few per cent apart is faster (the speed log has several it
ranked wrongly, Clang 22 against Clang 19 on both machines among them). ``--where N`` also lists
where in the source the instructions came from: by step (the line of trace_level(), trace() or
render_tile_packets() each was inlined from, read from the core's inlining chains by addr2line)
and by the innermost function. ``--mnemonics N`` lists the N most executed mnemonics a packet,
how many of each on 512-bit registers, and the operands a packet that name the stack (spills,
reloads, locals kept in memory): traffic the model leaves out. ``--listing FILE`` writes every
executed instruction of the packets to FILE with its innermost function, line and step, to read
what the tables only count.

Needs gdb, binutils (nm, objdump, addr2line) and llvm-mca-19 (Debian: ``apt-get install gdb
binutils llvm-19``), which ``make`` does not install, and a core with symbols and line tables:
core_with_symbols() builds one (Clang 19, as ``make``) in build/packet-model.
"""

from __future__ import annotations

import argparse
import functools
import os
import re
import shutil
import subprocess
import sys
import tempfile
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from reference.core_build import ROOT, BuildError, build_core, load_core, make_cxx

#: render_tile_packets()'s symbol: the tile loop into which trace() and trace_level() are inlined.
TILE_SYMBOL = "_ZN2rt19render_tile_packetsERKNS_13PacketCullingERKNS_5SceneEiiiiPfRNS_9RayCountsE"

#: The vector additions, subtractions, multiplications, divisions and square roots of doubles.
VECTOR_ARITHMETIC = re.compile(r"^v(add|sub|mul|div|sqrt)pd$")

# gdb's own Python: skip IGNORE pixel stores, stop at the next (that of packet IGNORE, 0-based),
# then step through PACKETS more, writing each instruction's offset in the core and its text.
GDB_SCRIPT = """
import gdb, os
sym, store, fn_off = os.environ["PM_SYMBOL"], int(os.environ["PM_STORE"], 16), \\
    int(os.environ["PM_FN"], 16)
ignore, packets, out = int(os.environ["PM_IGNORE"]), int(os.environ["PM_PACKETS"]), \\
    open(os.environ["PM_OUT"], "w")
for c in ("set pagination off", "set confirm off", "set breakpoint pending on",
          "set disassembly-flavor att", f"break {sym}"):
    gdb.execute(c)
gdb.execute("run", to_string=True)
base = int(gdb.parse_and_eval(f"(long)&{sym}")) - fn_off
gdb.execute("delete")
gdb.execute(f"break *{base + store:#x}")
if ignore > 0:
    gdb.execute(f"ignore 2 {ignore}")
gdb.execute("continue", to_string=True)
done = 0
while done < packets:
    gdb.execute("stepi", to_string=True)
    pc = int(gdb.parse_and_eval("$pc"))
    if pc == base + store:
        done += 1
        out.write("#packet\\n")
        continue
    text = gdb.execute(f"x/i {pc:#x}", to_string=True).strip().replace("=> ", "")
    out.write(f"{pc - base:x}\\t{text.split(':', 1)[1].strip()}\\n")
out.close()
gdb.execute("kill")
"""

# The traced process: Ex 25 rendered over and over on one thread by the core at argv[1].
RENDER_LOOP = """
import sys, time
from reference.core_build import load_core
core_module = load_core(sys.argv[1])
from reference.bench import ex25_scene
from tracer.render import core_integrator, to_core
scene = ex25_scene(int(sys.argv[2]), int(sys.argv[3]))
core, integrator = to_core(scene), core_integrator(scene, True)
start = time.perf_counter()
while time.perf_counter() - start < 600:
    core_module.render(core, 1, None, integrator, True)
"""


class ModelError(RuntimeError):
    """A tool missing, a core without the symbols needed, or a trace that did not come."""


def tile_side(width: int, height: int, threads: int = 1) -> int:
    """11_render.h tile_side(): 16, or 8 where tiles of 16 would give each thread fewer than 16."""
    tiles = -(-width // 16) * -(-height // 16)
    return 16 if tiles >= 16 * threads else 8


#: Whether the render fills the tile of columns [x0, x1) and rows [y0, y1) without a packet.
TileFilled = Callable[[int, int, int, int], bool]


def packet_index(x: int, y: int, width: int, height: int, rays_per_packet: int,
                 filled: TileFilled | None = None) -> int:  # fmt: skip
    """The 0-based place, in a one-thread render of one sample a pixel, of the packet that holds
    pixel (x, y): 11_render.h's one worker takes the tiles in order, row of tiles by row of
    tiles, and 12_packet.h render_tile_packets() a tile's rows top down, each in packets of
    rays_per_packet pixels from its left edge (the last one of a row maybe shorter). A tile
    that `filled` names (the core's tile_filled(): the sky, coloured without a ray) holds no
    packet; a pixel in one has none, and raises ValueError."""
    if not (0 <= x < width and 0 <= y < height):
        raise ValueError(f"pixel ({x}, {y}) is outside the {width}x{height} image")
    side = tile_side(width, height)
    tiles_x = -(-width // side)

    def packets_in(tx: int, ty: int, rows: int) -> int:  # in the first `rows` rows of a tile
        tile_w, tile_h = min(side, width - tx * side), min(side, height - ty * side)
        if filled is not None and filled(tx * side, ty * side, tx * side + tile_w,
                                         ty * side + tile_h):  # fmt: skip
            return 0
        return min(rows, tile_h) * -(-tile_w // rays_per_packet)

    tile_x, tile_y = x // side, y // side
    if packets_in(tile_x, tile_y, side) == 0:
        raise ValueError(f"pixel ({x}, {y}) lies in a tile filled with the background without "
                         "a ray traced: pick a pixel that sees something")  # fmt: skip
    before = sum(packets_in(tx, ty, side) for ty in range(tile_y) for tx in range(tiles_x))
    before += sum(packets_in(tx, tile_y, side) for tx in range(tile_x))
    return before + packets_in(tile_x, tile_y, y - tile_y * side) + (x % side) // rays_per_packet


def trace_to_asm(lines: list[str]) -> str:
    """A trace's instructions (``offset<TAB>text`` lines as gdb printed them) as assembly that
    llvm-mca reads: gdb's comments and symbol names dropped, every jump aimed at one label at
    the top (the model runs the block straight through, as if every branch were foreseen), and
    calls left out (a call leaves the traced function; its instructions follow in the trace)."""
    out = [".Ltrace:"]
    for line in lines:
        if "\t" not in line:
            continue
        text = line.split("\t", 1)[1].split("#")[0]
        text = re.sub(r"\s*<[^>]*>", "", text).strip()
        jump = re.match(r"(j[a-z]+)\s", text)
        if text.startswith("call"):
            continue
        out.append(f"  {jump.group(1)} .Ltrace" if jump else f"  {text}")
    return "\n".join(out) + "\n"


@dataclass
class CoreModel:
    """llvm-mca's account of a block on one processor."""

    cpu: str
    instructions: int
    cycles: int
    iterations: int
    bottlenecks: dict[str, float]  # resource: share of cycles it held back (per cent)

    def per_iteration(self) -> float:
        return self.cycles / self.iterations


def parse_mca(cpu: str, text: str) -> CoreModel:
    """llvm-mca's summary (with -bottleneck-analysis): its totals and resource pressures."""

    def number(label: str) -> int:
        found = re.search(rf"^{label}:\s+(\d+)", text, re.M)
        if found is None:
            raise ModelError(f"llvm-mca for {cpu} printed no {label!r}:\n{text[:2000]}")
        return int(found.group(1))

    section = text.split("Resource Pressure", 1)[1] if "Resource Pressure" in text else ""
    bottlenecks = {
        m.group(1): float(m.group(2))
        for m in re.finditer(r"^\s+-\s+(\S+)\s+\[\s*([\d.]+)%\s*\]", section.split("\n\n")[0], re.M)
    }
    return CoreModel(cpu, number("Instructions"), number("Total Cycles"), number("Iterations"),
                     bottlenecks)  # fmt: skip


def _tool(name: str) -> str:
    found = shutil.which(name)
    if found is None:
        raise ModelError(f"{name} is not installed (Debian: apt-get install gdb binutils llvm-19)")
    return found


def packet_store(listing: str, source_line: Callable[[int], str]) -> int | None:
    """In objdump's listing of render_tile_packets(), where a whole packet's colours become
    floats: the first conversion of the widest vectors the build has whose source line
    (`source_line(address)`, from the core's line tables) is store_pixels()'s
    __builtin_convertvector() of a packet's colour. (The compiler may interleave the three
    with other work, and it converts vectors elsewhere too: a sample's sum, a short packet. It
    may also read the colour from the stack, `vcvtpd2ps 0x540(%rsp),%ymm0`: then the width is
    the destination's one size up, or objdump's x/y suffix names it.)"""
    found = []
    pattern = r"^\s*([0-9a-f]+):\s+vcvtpd2ps([xy]?)\s+(%([xyz])mm\d+|[^,\s]*\([^)]*\)),%([xyz])mm"
    for address, suffix, _, source, destination in re.findall(pattern, listing, re.M):
        width = source or suffix or {"y": "z", "x": "y"}.get(destination, "x")
        found.append((address, width))
    for width in "zyx":
        for address in (int(a, 16) for a, w in found if w == width):
            if "__builtin_convertvector(c." in source_line(address):
                return address
    return None


def store_offsets(so: Path) -> tuple[int, int]:
    """render_tile_packets()'s offset in the core and that of its first conversion of a whole
    packet's colours to float (store_pixels(), inlined: one per packet of one sample a pixel)."""
    symbols = subprocess.run(
        [_tool("nm"), "--print-size", str(so)], capture_output=True, text=True, check=True
    )
    found = re.search(rf"^([0-9a-f]+) ([0-9a-f]+) [tT] {TILE_SYMBOL}$", symbols.stdout, re.M)
    if found is None:
        raise ModelError(f"{so}: no symbol render_tile_packets (a core built without symbols?)")
    fn, size = int(found.group(1), 16), int(found.group(2), 16)
    listing = subprocess.run(
        [_tool("objdump"), "-d", "--no-show-raw-insn", f"--start-address={fn:#x}",
         f"--stop-address={fn + size:#x}", str(so)],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    conversions = re.findall(r"^\s*([0-9a-f]+):\s+vcvtpd2ps", listing.stdout, re.M)
    places = source_places(so, [int(a, 16) for a in conversions])

    def source_line(address: int) -> str:
        chain = places.get(address)
        return source_text(chain[0][1]) if chain else ""

    store = packet_store(listing.stdout, source_line)
    if store is None:
        raise ModelError(
            f"{so}: no packet's store found in render_tile_packets (a core without line tables? "
            "store_pixels() changed?)"
        )
    return fn, store


def core_with_symbols() -> Path:
    """The core built as `make` builds it (Clang 19, -O3, this machine's vector units) but with
    its symbols and line tables (RelWithDebInfo; the compile options the CMakeLists gives,
    -O3 among them, come after the build type's), in build/packet-model: the installed core,
    like nanobind's every release build, has its symbols stripped."""
    compiler = f"-DCMAKE_CXX_COMPILER={_tool(make_cxx())}"
    try:
        return build_core(ROOT / "build" / "packet-model", compiler, build_type="RelWithDebInfo").so
    except BuildError as error:
        raise ModelError(str(error)) from error


def trace_packets(so: Path, x: int, y: int, packets: int, width: int, height: int,
                  rays_per_packet: int,
                  filled: TileFilled | None = None) -> list[list[str]]:  # fmt: skip
    """The instructions of `packets` packets from the one holding pixel (x, y), one list each
    (`filled`: packet_index()'s)."""
    fn, store = store_offsets(so)
    try:
        first = packet_index(x, y, width, height, rays_per_packet, filled)
    except ValueError as e:  # a pixel outside the image, or in a tile that holds no packet
        raise ModelError(str(e)) from e
    if first == 0:
        raise ModelError("the first packet has no store before it to stop at: pick another pixel")
    with tempfile.TemporaryDirectory() as tmp:
        script, out, loop = Path(tmp, "trace.py"), Path(tmp, "trace.txt"), Path(tmp, "loop.py")
        script.write_text(GDB_SCRIPT)
        loop.write_text(RENDER_LOOP)
        env = {**os.environ, "PM_SYMBOL": TILE_SYMBOL, "PM_STORE": f"{store:x}",
               "PM_FN": f"{fn:x}", "PM_PACKETS": str(packets),
               "PM_IGNORE": str(first - 1), "PM_OUT": str(out),
               "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": "1"}  # fmt: skip
        done = subprocess.run(
            [_tool("gdb"), "-q", "-batch", "-x", str(script), "--args", sys.executable,
             str(loop), str(so), str(width), str(height)],
            env=env, cwd=ROOT, capture_output=True, text=True, timeout=1800,
        )  # fmt: skip
        if not out.exists():
            raise ModelError(f"gdb wrote no trace:\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}")
        lines = out.read_text().splitlines()
    # From packet first - 1's store to packet first's is the end of that store and the whole
    # of packet first: each stretch between two stores is one packet.
    chunks: list[list[str]] = [[]]
    for line in lines:
        if line == "#packet":
            chunks.append([])
        else:
            chunks[-1].append(line)
    whole = chunks[:packets]
    if len(whole) < packets or not all(whole):
        raise ModelError(f"the trace holds {len(whole)} whole packets of the {packets} asked for")
    return whole


def source_places(so: Path, offsets: list[int]) -> dict[int, list[tuple[str, str]]]:
    """Each offset's chain of inlined source functions, innermost first, by one addr2line run."""
    unique = sorted(set(offsets))
    done = subprocess.run(
        [_tool("addr2line"), "-a", "-f", "-i", "-C", "-e", str(so)],
        input="\n".join(f"{o:#x}" for o in unique), capture_output=True, text=True, check=True,
    )  # fmt: skip
    return parse_addr2line(done.stdout)


def parse_addr2line(text: str) -> dict[int, list[tuple[str, str]]]:
    """addr2line -a -f -i output read back: after each address line (0x...), pairs of a function
    and a path:line, innermost first (the first pair's line is the instruction's own, each
    further pair's the line in that function that the pair before was inlined at). Functions
    lose their arguments and the rt:: prefix, lines their discriminators; paths stay whole, so
    that a core built from another tree (--so) is read against that tree's sources."""
    places: dict[int, list[tuple[str, str]]] = {}
    chain: list[tuple[str, str]] = []
    lines = text.splitlines()
    k = 0
    while k < len(lines):
        if re.fullmatch(r"0x[0-9a-f]+", lines[k]):
            chain = places.setdefault(int(lines[k], 16), [])
            k += 1
            continue
        function = re.sub(r"\(.*", "", lines[k]).removeprefix("rt::")
        path, _, line = (
            (lines[k + 1] if k + 1 < len(lines) else "??:0").partition(" ")[0].rpartition(":")
        )
        chain.append((function, f"{path}:{line}"))
        k += 2
    return places


#: The functions whose lines name a step of the classic algorithm, the most specific first: an
#: instruction is counted at the line of the first of these its inlining chain passes through.
STEP_FUNCTIONS = ("trace_level", "trace", "render_tile_packets")


def step_of(chain: list[tuple[str, str]]) -> str:
    """The step an instruction belongs to: `file:line` in the first of STEP_FUNCTIONS met
    going outward along its inlining chain (the line inside that function)."""
    for wanted in STEP_FUNCTIONS:
        for function, place in chain:
            if function == wanted:
                return f"{place} {function}"
    return "?"


def where_time_goes(lines: list[str], places: dict[int, list[tuple[str, str]]], top: int,
                    source: Callable[[str], str] = lambda place: "") -> str:  # fmt: skip
    """The trace's instructions and vector arithmetic by step (the line of trace_level(),
    trace() or render_tile_packets() they were inlined from) and by innermost function, the
    `top` largest of each; `source(place)` gives a step's source text."""
    counts: dict[str, Counter[str]] = {"step": Counter(), "function": Counter()}
    arith: dict[str, Counter[str]] = {"step": Counter(), "function": Counter()}
    total = 0
    for line in lines:
        if "\t" not in line:
            continue
        offset, text = line.split("\t", 1)
        chain = places.get(int(offset, 16), [])
        vector = int(bool(VECTOR_ARITHMETIC.match(text.split()[0])))
        for kind, key in (("step", step_of(chain)), ("function", chain[0][0] if chain else "?")):
            counts[kind][key] += 1
            arith[kind][key] += vector
        total += 1
    out = []
    for kind in ("step", "function"):
        out.append(f"  {'instructions':>12} {'vector arith':>12}  {kind}")
        for key, n in counts[kind].most_common(top):
            text = source(key) if kind == "step" else ""
            shown = Path(key).name if kind == "step" else key  # the step's file, not its folders
            out.append(f"  {n:7d} {100 * n / total:3.0f}% {arith[kind][key]:12d}  {shown}"
                       + (f"  {text}" if text else ""))  # fmt: skip
    return "\n".join(out)


def listing(packets: list[list[str]], places: dict[int, list[tuple[str, str]]]) -> str:
    """The traced packets instruction by instruction, in the order executed: each with the
    innermost function and line it came from and its step (step_of()), a `# packet k` line
    before each packet. What where_time_goes() counts, to be read: which values a packet spills
    and reloads, what a branch or a dispatch costs where it runs."""
    out = []
    for k, packet in enumerate(packets):
        out.append(f"# packet {k}")
        for line in packet:
            if "\t" not in line:
                continue
            offset, text = line.split("\t", 1)
            chain = places.get(int(offset, 16), [])
            inner = f"{chain[0][0]} {Path(chain[0][1]).name}" if chain else "?"
            step = step_of(chain)
            out.append(f"{text:<56} {inner:<36} {Path(step).name if chain else step}")
    return "\n".join(out) + "\n"


# An operand that names the stack: a spill, its reload, or a local kept in memory.
STACK_OPERAND = re.compile(r"\(%r[sb]p\)|\(%r[sb]p,")


def mnemonic_mix(lines: list[str], packets: int, top: int) -> str:
    """The `top` most executed mnemonics a packet, each with how many of them name a 512-bit
    register, and the operands a packet that name the stack (rsp or rbp)."""
    counts: Counter[str] = Counter()
    wide: Counter[str] = Counter()
    stack = 0
    for line in lines:
        if "\t" not in line:
            continue
        text = line.split("\t", 1)[1]
        mnemonic = text.split()[0]
        counts[mnemonic] += 1
        wide[mnemonic] += "%zmm" in text
        stack += len(STACK_OPERAND.findall(text))
    out = [f"  {'a packet':>9} {'on zmm':>7}  mnemonic"]
    for mnemonic, n in counts.most_common(top):
        out.append(f"  {n / packets:9.1f} {wide[mnemonic] / packets:7.1f}  {mnemonic}")
    out.append(f"  {stack / packets:9.1f} {'':>7}  operands naming the stack (rsp, rbp)")
    return "\n".join(out)


def model(asm: str, cpu: str, iterations: int = 20) -> CoreModel:
    """The block timed by llvm-mca-19 on its model of `cpu` (repeated `iterations` times)."""
    done = subprocess.run(
        [_tool("llvm-mca-19"), f"-mcpu={cpu}", f"-iterations={iterations}",
         "-bottleneck-analysis", "-instruction-info=false", "-resource-pressure=false"],
        input=asm, capture_output=True, text=True,
    )  # fmt: skip
    if done.returncode != 0:
        raise ModelError(f"llvm-mca-19 -mcpu={cpu} failed:\n{done.stderr[-2000:]}")
    return parse_mca(cpu, done.stdout)


@functools.cache
def _source_file(path: str) -> list[str]:
    return Path(path).read_text().splitlines() if Path(path).is_file() else []


def source_text(place: str) -> str:
    """The source line at `place` (``path:line``, anything after a space ignored: a step's
    function), stripped; empty where the file or the line is unknown."""
    path, _, line = place.split(" ")[0].rpartition(":")
    text = _source_file(path)
    return text[int(line) - 1].strip() if line.isdigit() and 0 < int(line) <= len(text) else ""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m reference.packet_model",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--so",
        type=Path,
        help="the core to trace (default: one built as make builds it, with symbols)",
    )
    parser.add_argument(
        "--pixel", type=int, nargs=2, default=(160, 705), metavar=("X", "Y"),
        help="the first packet's pixel (default: floor, left of the red sphere)",
    )  # fmt: skip
    parser.add_argument("--packets", type=int, default=4)
    parser.add_argument(
        "--cpu", action="append",
        help="llvm-mca's -mcpu (default: znver4 and sapphirerapids, this machine class's two)",
    )  # fmt: skip
    parser.add_argument("--size", type=int, nargs=2, default=(1920, 1024), metavar=("W", "H"))
    parser.add_argument(
        "--where", type=int, default=0, metavar="N",
        help="also list the N steps (lines of trace_level(), trace() or render_tile_packets()) "
        "and the N innermost functions the most instructions came from",
    )  # fmt: skip
    parser.add_argument(
        "--listing", type=Path, metavar="FILE",
        help="also write every executed instruction of the packets, with its source line and "
        "step, to FILE",
    )  # fmt: skip
    parser.add_argument(
        "--mnemonics", type=int, default=0, metavar="N",
        help="also list the N most executed mnemonics a packet (how many on 512-bit registers) "
        "and the operands a packet that name the stack",
    )  # fmt: skip
    args = parser.parse_args(argv)
    try:
        so = args.so or core_with_symbols()
        # Loaded here as the traced process loads it, for its packet width.
        core_module = load_core(so)
        width, height = args.size
        from reference.bench import ex25_scene
        from tracer.render import to_core

        core = to_core(ex25_scene(width, height))  # the traced process's scene

        def filled(x0: int, y0: int, x1: int, y1: int) -> bool:
            return bool(core_module.tile_filled(core, x0, y0, x1, y1))

        packets = trace_packets(so, *args.pixel, args.packets, width, height,
                                core_module.rays_per_packet, filled)  # fmt: skip
        lines = [line for packet in packets for line in packet]
        mnemonics = Counter(line.split("\t", 1)[1].split()[0] for line in lines)
        arithmetic = sum(n for m, n in mnemonics.items() if VECTOR_ARITHMETIC.match(m))
        n = len(packets)
        print(f"{so}: {n} packets of {core_module.rays_per_packet} rays from pixel "
              f"{tuple(args.pixel)}: {len(lines) / n:.0f} instructions a packet, "
              f"{arithmetic / n:.0f} of them vector add/sub/mul/div/sqrt")  # fmt: skip
        if args.where > 0 or args.listing is not None:
            offsets = [int(line.split("\t", 1)[0], 16) for line in lines if "\t" in line]
            places = source_places(so, offsets)
            if args.where > 0:
                print(where_time_goes(lines, places, args.where, source_text))
            if args.listing is not None:
                from tracer.image import atomic_path

                with atomic_path(args.listing) as tmp:
                    tmp.write_text(listing(packets, places))
                print(f"{args.listing}: {len(lines)} instructions, {n} packets")
        if args.mnemonics > 0:
            print(mnemonic_mix(lines, n, args.mnemonics))
        for cpu in args.cpu or ["znver4", "sapphirerapids"]:
            m = model(trace_to_asm(lines), cpu)
            held = ", ".join(f"{r} {p:.0f}%" for r, p in
                             sorted(m.bottlenecks.items(), key=lambda kv: -kv[1])[:3])  # fmt: skip
            print(
                f"  {cpu:<12} {m.per_iteration() / n:7.0f} cycles a packet, "
                f"{m.instructions / m.cycles:.2f} instructions a cycle; held back by {held}"
            )
    except ModelError as e:
        print(f"packet_model: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
