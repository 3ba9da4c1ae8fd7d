"""The ``rtlab`` command line."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from tracer import interrupt
from tracer.image import ImageFormatError, image_format, save_aov, save_image
from tracer.render import ImageTooLargeError, aov_channels, render_progressive, render_with_stats
from tracer.scene import Scene, SceneError, load_scene
from tracer.scene.values import suggest

# The demo scene lives with the scenes; re-exported here, where tests and users call it.
from tracer.scenes import DEMO_SCENE as DEMO_SCENE
from tracer.scenes import demo_scene_path as demo_scene_path


class UsageError(ValueError):
    """A command line the verbs cannot run (an unknown renderer or suite): not about a scene."""


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a number >= 1, got {value}")
    return value


def _duration(text: str) -> float:
    """'10s', '2m', '500ms', '1h' or a plain number of seconds."""
    units = {"ms": 1e-3, "s": 1.0, "m": 60.0, "h": 3600.0}
    for suffix in ("ms", "s", "m", "h"):
        if text.endswith(suffix):
            number, scale = text[: -len(suffix)], units[suffix]
            break
    else:
        number, scale = text, 1.0
    try:
        value = float(number) * scale
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected a duration like 10s or 2m, got {text!r}"
        ) from None
    if not 0 < value < float("inf"):  # also refuses nan, and inf, which would never end
        raise argparse.ArgumentTypeError(f"expected a positive, finite duration, got {text!r}")
    return value


def _add_overrides(p: argparse.ArgumentParser) -> None:
    p.add_argument("--width", type=_positive_int, help="image width in pixels")
    p.add_argument("--height", type=_positive_int, help="image height in pixels")
    p.add_argument("--spp", type=_positive_int, help="samples per pixel")
    p.add_argument("--seed", type=int, help="random seed for jittered samples")
    p.add_argument("--max-depth", type=_positive_int, help="levels of the ray tree")
    p.add_argument("--threads", type=_positive_int, help="render threads (default: all cores)")
    p.add_argument("--quiet", action="store_true", help="no progress bar, no summary")


def _apply_overrides(scene: Scene, args: argparse.Namespace) -> Scene:
    return scene.with_overrides(
        width=args.width,
        height=args.height,
        spp=args.spp,
        seed=args.seed,
        max_depth=args.max_depth,
    )


def _render_to(scene: Scene, outputs: Sequence[Path], args: argparse.Namespace) -> None:
    aov = scene.render.integrator == "aov"
    for out in outputs:  # refuse a bad suffix before spending time on the render
        if image_format(out) == ".png" and aov:
            raise ImageFormatError(f"{out}: an aov render has no colours to show; use .exr or .npy")
    budget = getattr(args, "time", None)
    if budget is not None:
        result = render_progressive(
            scene, budget, threads=args.threads, progress=None if not args.quiet else False
        )
    else:
        result = render_with_stats(
            scene, threads=args.threads, progress=None if not args.quiet else False
        )
    for out in outputs:
        if aov:
            save_aov(out, aov_channels(result.image))
        else:
            save_image(out, result.image)
        _WRITTEN.append(out)
    if not args.quiet:
        rays = result.rays
        total = rays["primary"] + rays["secondary"] + rays["shadow"]
        stereo = scene.camera.stereo
        eyes = 2 if stereo is not None and stereo.layout not in ("left", "right") else 1
        pixels = scene.camera.width * scene.camera.height * eyes
        print(
            f"{scene.camera.width}x{scene.camera.height}{' per eye' if eyes == 2 else ''}, "
            f"{rays['primary'] // pixels} spp, "
            f"{result.threads} threads: {result.seconds:.3f} s, {total / 1e6:.2f} M rays "
            f"({rays['primary']} primary, {rays['secondary']} secondary, {rays['shadow']} shadow); "
            f"{rays['box_tests']} ray/box and {rays['primitive_tests']} ray/primitive tests"
        )
        for out in outputs:
            print(f"wrote {out}")


def cmd_render(args: argparse.Namespace) -> None:
    scene = _apply_overrides(load_scene(args.scene), args)
    _render_to(scene, [Path(args.output)], args)


def _agreement_status(rows: list[dict]) -> int:
    """1 (and why, on stderr) when a reference disagrees with rtlab, else 0: the exit status of
    compare and demo."""
    disagree = [r for r in rows if r.get("agrees") is False]
    for r in disagree:
        print(f"rtlab: {r['renderer']} disagrees with rtlab: {r['verdict']}", file=sys.stderr)
    if disagree:
        print("rtlab: exit status 1: the renderers disagree", file=sys.stderr)
    return 1 if disagree else 0


def cmd_demo(args: argparse.Namespace) -> int:
    scene = _apply_overrides(load_scene(demo_scene_path()), args)
    out = Path(args.out_dir)
    if args.rtlab_only:
        _render_to(scene, [out / "ex25-rtlab.png", out / "ex25-rtlab.exr"], args)
        return 0
    from reference.compare import REFERENCES, compare_scene, format_table

    rows = compare_scene(scene, REFERENCES, out_dir=out, json_path=out / "ex25-metrics.json",
                         threads=args.threads, stem="ex25")  # fmt: skip
    print(format_table(rows))
    print(f"images: {out}/ex25-rtlab.png (rtlab), ex25-povray.png, ex25-mitsuba-*.png;")
    print(f"heat maps: {out}/ex25-diff-*.png; metrics: {out}/ex25-metrics.json")
    return _agreement_status(rows)


def _classic_only(scene: Scene, what: str) -> None:
    if scene.render.integrator != "classic":
        raise SceneError(
            scene.source, "render.integrator",
            f"{what} reproduces the classic model only, and this scene's integrator is "
            f"{scene.render.integrator!r} (path scenes convert to Mitsuba)",
        )  # fmt: skip


def cmd_convert(args: argparse.Namespace) -> None:
    scene = _apply_overrides(load_scene(args.scene), args)
    if args.to == "povray":
        _classic_only(scene, "POV-Ray")
        from converters.povray import write_povray

        path = write_povray(scene, args.output)
        how = f"render with: povray +I{path} +W{scene.camera.width} +H{scene.camera.height} -D -A"
    else:
        from converters.mitsuba import write_mitsuba_xml

        path = write_mitsuba_xml(scene, args.output)
        how = "load with mi.load_file after 'import converters.mitsuba'"
    if not args.quiet:
        print(f"wrote {path} ({how})")


def cmd_compare(args: argparse.Namespace) -> int:
    from reference.compare import REFERENCES, compare_scene, format_table

    against = tuple(a.strip() for a in args.against.split(",") if a.strip())
    for name in against:
        if name not in REFERENCES:
            raise UsageError(
                f"--against: unknown renderer {name!r}{suggest(name, REFERENCES)}; "
                f"expected a comma-separated list of {', '.join(REFERENCES)}"
            )
    if args.html and not args.out_dir:
        raise UsageError("--html: the page goes beside the images: give --out-dir too")
    if args.single_file and not args.html:
        raise UsageError("--single-file: it inlines the page's images: give --html too")
    scene = _apply_overrides(load_scene(args.scene), args)
    if "povray" in against:
        _classic_only(scene, "POV-Ray")
    if scene.render.integrator == "aov":
        message = "an aov scene has no image to compare; render it with rtlab render"
        raise SceneError(scene.source, "render.integrator", message)
    rows = compare_scene(
        scene, against, out_dir=args.out_dir, json_path=args.json, threads=args.threads,
        progress=None if not args.quiet else False, written=_WRITTEN,
    )  # fmt: skip
    print(format_table(rows))
    if args.out_dir:
        print(f"images and heat maps in {args.out_dir}/")
    if args.json:
        print(f"metrics in {args.json}")
    if args.html:
        import shlex

        from reports.compare_page import write_compare_page

        command = "rtlab " + " ".join(shlex.quote(a) for a in sys.argv[1:]) if sys.argv[1:] else ""
        page = write_compare_page(scene, rows, args.out_dir, command=command or "rtlab compare",
                                  json_path=args.json, inline=args.single_file)  # fmt: skip
        print(f"the page: {page}")
    return _agreement_status(rows)


def cmd_bench(args: argparse.Namespace) -> None:
    from reference.bench import SUITES, format_ratios, run_suites
    from tracer.image import atomic_path

    if args.summarize:
        if args.suite is not None or args.runs != 1:
            raise UsageError("bench: --summarize reads runs already made: give no suite, no --runs")
        _bench_summary(args, args.summarize, "rtlab bench --summarize " + " ".join(args.summarize))
        return
    if args.suite is None:
        raise UsageError(f"bench: which suite? expected all or {', '.join(SUITES)}")
    names = list(SUITES) if args.suite == "all" else [args.suite]
    if names[0] not in SUITES:
        raise UsageError(
            f"bench: unknown suite {args.suite!r}{suggest(args.suite, [*SUITES, 'all'])}; "
            f"expected all or {', '.join(SUITES)}"
        )
    from tracer.batch import Engine

    engine = Engine(args.workers, args.scheduler) if args.workers or args.scheduler else None
    command = f"rtlab bench {args.suite}" + (f" --runs {args.runs}" if args.runs > 1 else "")
    command += f" --json {args.json}" if args.json else ""
    if args.runs > 1:
        # Each run whole, one after the other (its renderers taking turns within it); the rows
        # of all runs go to one file, each with its run's number.
        runs = []
        out_dir = Path(args.json).parent if args.json else None  # the convergence plots
        for number in range(1, args.runs + 1):
            print(f"run {number} of {args.runs}", flush=True)
            made = run_suites(names, None, engine, out_dir=out_dir)
            runs.append([{**r, "run": number} for r in made])
        if args.json:
            with atomic_path(args.json) as tmp:
                tmp.write_text(json.dumps([r for run in runs for r in run], indent=2) + "\n")
        _print_summary(args, runs, command)
        return
    rows = run_suites(names, args.json, engine)  # engine: the convergence suite's (a case a task)
    print(format_ratios(rows))
    if args.json:
        print(f"rows in {args.json}")
    if args.markdown:
        from reference.bench import format_markdown

        _write_table(args.markdown, format_markdown(rows, command))


def _bench_summary(args: argparse.Namespace, paths: list[str], command: str) -> None:
    """`rtlab bench --summarize FILE...`: the runs in those files, summarised."""
    from reference.bench import RunsError, read_runs

    if args.json:
        raise UsageError("bench: --summarize writes no rows (--json); --markdown writes its table")
    try:
        runs = read_runs(paths)
    except RunsError as exc:
        raise UsageError(f"bench: {exc}") from exc
    _print_summary(args, runs, command)


def _print_summary(args: argparse.Namespace, runs: list[list[dict]], command: str) -> None:
    from reference.bench import format_summary, format_summary_markdown

    print(format_summary(runs))
    if args.json:
        print(f"rows of the {len(runs)} runs in {args.json}")
    if args.markdown:
        _write_table(args.markdown, format_summary_markdown(runs, command))


def _write_table(path: str, table: str) -> None:
    from tracer.image import atomic_path

    with atomic_path(path) as tmp:
        tmp.write_text(table)
    print(f"table in {path}")


def cmd_view(args: argparse.Namespace) -> int:
    from tracer.viewer.server import serve

    try:
        serve(args.scene, args.host, args.port, not args.no_browser, args.threads)
    except KeyboardInterrupt:  # Ctrl-C is how a viewer stops: not a failure
        interrupt.handled()
        print("rtlab view: stopped", file=sys.stderr)
    except OSError as exc:  # the port is taken, the address is not this machine's
        raise UsageError(f"view: cannot listen on {args.host}:{args.port}: {exc}") from exc
    return 0


def cmd_check(args: argparse.Namespace) -> None:
    scene = load_scene(args.scene)
    print(
        f"{args.scene}: ok ({len(scene.objects)} objects, {len(scene.lights)} lights, "
        f"{len(scene.materials)} materials)"
    )


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="rtlab", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("render", help="render a scene file to .exr, .png or .npy")
    p.add_argument("scene", help="scene file (TOML)")
    p.add_argument("-o", "--output", required=True, help="output image: .exr, .png or .npy")
    p.add_argument("--time", type=_duration, help="render passes until this time is spent (10s)")
    _add_overrides(p)
    p.set_defaults(func=cmd_render)

    p = sub.add_parser(
        "demo",
        help="render the built-in demo scene (the course's Ex 25) with all three renderers; "
        "exit 1 if they disagree",
    )
    p.add_argument("--out-dir", default="out", help="where the images go (default: out)")
    p.add_argument("--rtlab-only", action="store_true", help="only rtlab's render")
    _add_overrides(p)
    p.set_defaults(func=cmd_demo)

    p = sub.add_parser("convert", help="write the scene for POV-Ray (SDL) or Mitsuba 3 (XML)")
    p.add_argument("scene", help="scene file (TOML)")
    p.add_argument("--to", required=True, choices=("povray", "mitsuba"), help="target renderer")
    p.add_argument("-o", "--output", required=True, help="output file (.pov or .xml)")
    _add_overrides(p)
    p.set_defaults(func=cmd_convert)

    p = sub.add_parser(
        "compare",
        help="render with rtlab and the references; metrics and maps; exit 1 if they disagree",
        description=COMPARE_DESCRIPTION,
    )
    p.add_argument("scene", help="scene file (TOML)")
    p.add_argument("--against", default="povray,mitsuba", help="povray, mitsuba or both")
    p.add_argument("--out-dir", help="write each image and a heat map per pair here")
    p.add_argument("--json", help="write the metrics here")
    p.add_argument(
        "--html",
        action="store_true",
        help="also write the comparison as a page, OUT_DIR/<scene>.html (needs --out-dir)",
    )
    p.add_argument(
        "--single-file",
        action="store_true",
        help="with --html: the page's images inlined as data: URIs (one file to mail)",
    )
    _add_overrides(p)
    p.set_defaults(func=cmd_compare)

    p = sub.add_parser("bench", help="speed side by side, as JSON rows and ratios")
    p.add_argument("suite", nargs="?", help="a suite name (classic) or all")
    p.add_argument("--json", help="write the rows here")
    p.add_argument("--markdown", help="write the figures as a Markdown table here (the README's)")
    p.add_argument(
        "--runs",
        type=_positive_int,
        default=1,
        help="run the suites this many times, one after the other; print and tabulate the "
        "medians and the range of rtlab's ratio (each ratio taken within one run)",
    )
    p.add_argument(
        "--summarize",
        nargs="+",
        metavar="JSON",
        help="summarise runs already made (files of --json, one run each or --runs' several) "
        "as --runs does, instead of running a suite",
    )
    from tracer.batch import add_engine_arguments  # convergence: each case a Dask task

    add_engine_arguments(p, default_serial=True, zero="no Dask")
    p.set_defaults(func=cmd_bench)

    p = sub.add_parser("view", help="a live view of a scene in the browser (mouse, keys, panel)")
    p.add_argument("scene", help="scene file (TOML); saving it re-renders")
    p.add_argument("--port", type=int, default=8765, help="port (default 8765; 0: a free one)")
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    p.add_argument("--no-browser", action="store_true", help="do not open a browser")
    p.add_argument("--threads", type=_positive_int, help="render threads (default: all cores)")
    p.set_defaults(func=cmd_view)

    p = sub.add_parser("check", help="validate a scene file without rendering")
    p.add_argument("scene", help="scene file (TOML)")
    p.set_defaults(func=cmd_check)

    p = sub.add_parser("lesson", help="the course's lessons: list, show, student trees")
    _add_lesson_arguments(p)
    p.set_defaults(func=cmd_lesson)

    p = sub.add_parser("report", help="the course's pages: a lesson's, or every lesson's")
    _add_report_arguments(p)
    p.set_defaults(func=cmd_report)

    p = sub.add_parser("study", help="numerical studies: stiff cases, every method side by side")
    _add_study_arguments(p)
    p.set_defaults(func=cmd_study)
    return parser


def _add_study_arguments(parser: argparse.ArgumentParser) -> None:
    from study.cli import add_arguments

    add_arguments(parser)


def cmd_study(args: argparse.Namespace) -> int:
    from study.cli import run

    return run(args)


def _add_report_arguments(parser: argparse.ArgumentParser) -> None:
    from reports.cli import add_arguments

    add_arguments(parser)


def cmd_report(args: argparse.Namespace) -> int:
    from reports.cli import run

    return run(args)


def _add_lesson_arguments(parser: argparse.ArgumentParser) -> None:
    from lessons.cli import add_arguments

    add_arguments(parser)


def cmd_lesson(args: argparse.Namespace) -> int:
    from lessons.cli import run

    return run(args)


COMPARE_DESCRIPTION = """Render a scene with rtlab and the reference renderers, print the metrics
of each reference against rtlab and whether it agrees: at most 0.05% of the pixels (0.3% for tori
against Mitsuba, which tessellates them) over the tolerance, the reference's output precision
(POV-Ray) or 1e-4 (Mitsuba), and no NaN or infinite pixel (reference/metrics.py). Exit status:
0 when every reference agrees, or no verdict is given (a path-traced scene, whose images are
compared statistically, or spp > 1, whose jittered samples differ); 1 when one disagrees; 2 for
bad input; 130 or 143 when interrupted by SIGINT or SIGTERM."""

#: The files this run has written, each complete: what an interruption leaves behind.
_WRITTEN: list[Path] = []


def _interrupted_message(signum: int) -> str:
    import signal

    name = "SIGINT (Ctrl-C)" if signum == signal.SIGINT else signal.Signals(signum).name
    if not _WRITTEN:
        return f"rtlab: interrupted by {name}; no output written"
    done = ", ".join(str(p) for p in _WRITTEN)
    return f"rtlab: interrupted by {name}; wrote only {done} (each complete), nothing else"


def main(argv: Sequence[str] | None = None) -> int:
    """Run one verb. Exit status: 0 done; 1 the renderers disagree (compare); 2 bad input;
    128 + the signal's number when interrupted (130 SIGINT, 143 SIGTERM), no output written."""
    import signal

    args = build_parser().parse_args(argv)
    _WRITTEN.clear()
    previous = interrupt.install()
    try:
        status = args.func(args) or 0
        interrupt.raise_if_interrupted()  # a signal whose exception was swallowed on the way
        return status
    except (SceneError, ImageFormatError, ImageTooLargeError, UsageError) as exc:
        print(f"rtlab: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        signum = getattr(exc, "signum", signal.SIGINT)
        print(_interrupted_message(signum), file=sys.stderr)
        return 128 + signum
    finally:
        interrupt.restore(previous)


if __name__ == "__main__":
    sys.exit(main())
