"""The ``rtlab`` command line."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from importlib import resources
from pathlib import Path

from tracer.image import ImageFormatError, image_format, save_aov, save_image
from tracer.render import ImageTooLargeError, aov_channels, render_progressive, render_with_stats
from tracer.scene import Scene, SceneError, load_scene

DEMO_SCENE = "ex25.toml"


def demo_scene_path() -> Path:
    return Path(str(resources.files("tracer") / "scenes" / DEMO_SCENE))


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
    if not value > 0:
        raise argparse.ArgumentTypeError(f"expected a positive duration, got {text!r}")
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
    if not args.quiet:
        rays = result.rays
        total = rays["primary"] + rays["secondary"] + rays["shadow"]
        print(
            f"{scene.camera.width}x{scene.camera.height}, "
            f"{rays['primary'] // (scene.camera.width * scene.camera.height)} spp, "
            f"{result.threads} threads: {result.seconds:.3f} s, {total / 1e6:.2f} M rays "
            f"({rays['primary']} primary, {rays['secondary']} secondary, {rays['shadow']} shadow); "
            f"{rays['box_tests']} ray/box and {rays['primitive_tests']} ray/primitive tests"
        )
        for out in outputs:
            print(f"wrote {out}")


def cmd_render(args: argparse.Namespace) -> None:
    scene = _apply_overrides(load_scene(args.scene), args)
    _render_to(scene, [Path(args.output)], args)


def cmd_demo(args: argparse.Namespace) -> None:
    scene = _apply_overrides(load_scene(demo_scene_path()), args)
    out = Path(args.out_dir)
    if args.rtlab_only:
        _render_to(scene, [out / "ex25-rtlab.png", out / "ex25-rtlab.exr"], args)
        return
    from reference.compare import REFERENCES, compare_scene, format_table

    rows = compare_scene(scene, REFERENCES, out_dir=out, json_path=out / "ex25-metrics.json",
                         threads=args.threads, stem="ex25")  # fmt: skip
    print(format_table(rows))
    print(f"images: {out}/ex25-rtlab.png (rtlab), ex25-povray.png, ex25-mitsuba-*.png;")
    print(f"heat maps: {out}/ex25-diff-*.png; metrics: {out}/ex25-metrics.json")


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


def cmd_compare(args: argparse.Namespace) -> None:
    from reference.compare import REFERENCES, compare_scene, format_table

    against = tuple(a.strip() for a in args.against.split(",") if a.strip())
    for name in against:
        if name not in REFERENCES:
            raise SceneError("--against", "", f"unknown renderer {name!r}; expected {REFERENCES}")
    scene = _apply_overrides(load_scene(args.scene), args)
    if "povray" in against:
        _classic_only(scene, "POV-Ray")
    if scene.render.integrator == "aov":
        message = "an aov scene has no image to compare; render it with rtlab render"
        raise SceneError(scene.source, "render.integrator", message)
    rows = compare_scene(
        scene, against, out_dir=args.out_dir, json_path=args.json, threads=args.threads
    )
    print(format_table(rows))
    if args.out_dir:
        print(f"images and heat maps in {args.out_dir}/")
    if args.json:
        print(f"metrics in {args.json}")


def cmd_bench(args: argparse.Namespace) -> None:
    from reference.bench import SUITES, format_ratios, run_suites

    names = list(SUITES) if args.suite == "all" else [args.suite]
    if names[0] not in SUITES:
        known = ", ".join(SUITES)
        raise SceneError("bench", "", f"unknown suite {args.suite!r}; expected all or {known}")
    rows = run_suites(names, args.json)
    print(format_ratios(rows))
    if args.json:
        print(f"rows in {args.json}")


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
        "demo", help="render the built-in demo scene (the course's Ex 25) with all three renderers"
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

    p = sub.add_parser("compare", help="render with rtlab and the references; metrics and maps")
    p.add_argument("scene", help="scene file (TOML)")
    p.add_argument("--against", default="povray,mitsuba", help="povray, mitsuba or both")
    p.add_argument("--out-dir", help="write each image and a heat map per pair here")
    p.add_argument("--json", help="write the metrics here")
    _add_overrides(p)
    p.set_defaults(func=cmd_compare)

    p = sub.add_parser("bench", help="speed side by side, as JSON rows and ratios")
    p.add_argument("suite", help="a suite name (classic) or all")
    p.add_argument("--json", help="write the rows here")
    p.set_defaults(func=cmd_bench)

    p = sub.add_parser("check", help="validate a scene file without rendering")
    p.add_argument("scene", help="scene file (TOML)")
    p.set_defaults(func=cmd_check)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        args.func(args)
    except (SceneError, ImageFormatError, ImageTooLargeError) as exc:
        print(f"rtlab: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("rtlab: interrupted; no output written", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
