"""``rtlab report lesson Lnn --out DIR | course --out DIR [--single-file] [--mistakes N] |
class GRADES --out DIR [--single-file]``: the verb's work (the parser's entry lives in
tracer/cli.py with the other verbs)."""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path

from lessons.catalog import LESSONS, UnknownLessonError, get_lesson
from reports.lesson import DEFAULT_MISTAKES, build_lesson_page


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="report_command", required=True)
    for name, text in (
        ("lesson", "one lesson's page: OUT/Lnn/index.html"),
        ("course", "every lesson's page and an index: OUT/index.html"),
    ):
        p = sub.add_parser(name, help=text)
        if name == "lesson":
            p.add_argument("lesson", help="a lesson id, e.g. L04")
        p.add_argument("--out", required=True, help="the site's directory, e.g. site/")
        p.add_argument(
            "--single-file",
            action="store_true",
            help="inline the images as data: URIs (a page to mail), no image files",
        )
        if name == "course":
            p.add_argument(
                "--study",
                choices=("none", "quick", "full"),
                default="none",
                help="also the stiff study (rtlab study stiff) in OUT/study/, linked from the "
                "precision lesson: quick takes about 40 s, full much longer (default none)",
            )
        p.add_argument(
            "--mistakes",
            type=int,
            default=DEFAULT_MISTAKES,
            help="known-wrong versions built and shown per lesson (default: every one; each "
            "costs a build of about 4 s unless cached in build/report-mistakes)",
        )
    p = sub.add_parser("class", help="an instructor's page over many results.json: OUT/index.html")
    p.add_argument("grades", help="a directory of results.json files, e.g. grades/<student>/")
    p.add_argument("--out", required=True, help="the page's directory, e.g. class/")
    p.add_argument(
        "--single-file",
        action="store_true",
        help="inline the score histogram as a data: URI (a page to mail), no image file",
    )


def run(args: argparse.Namespace) -> int:
    """Exit status: 0 done; 2 bad input (an unknown lesson, a negative --mistakes, a grades
    directory without results.json or with one that cannot be read)."""
    from reports.site import write_course_site, write_lesson_site

    command = "rtlab " + " ".join(shlex.quote(a) for a in sys.argv[1:]) if sys.argv[1:] else ""
    if args.report_command == "class":
        from reports.classpage import ClassReportError, write_class_page

        try:
            path = write_class_page(Path(args.grades), Path(args.out), command=command,
                                    inline=args.single_file)  # fmt: skip
        except ClassReportError as error:
            print(f"rtlab: error: {error}", file=sys.stderr)
            return 2
        print(f"rtlab: wrote {path} and its score histogram")
        return 0
    if args.mistakes is not None and args.mistakes < 0:
        print("rtlab: error: --mistakes: expected 0 or more", file=sys.stderr)
        return 2
    try:
        if args.report_command == "lesson":
            lesson = get_lesson(args.lesson).id
            command = command or f"rtlab report lesson {lesson} --out {args.out}"
            page = build_lesson_page(lesson, mistake_cap=args.mistakes, command=command)
            path = write_lesson_site(Path(args.out), page, inline=args.single_file)
            print(f"rtlab: wrote {path}: {len(page.scenes)} scenes, "
                  f"{len(page.mistakes_shown)} known-wrong versions rendered")  # fmt: skip
            return 0
        command = command or f"rtlab report course --out {args.out}"
        path = write_course_site(
            Path(args.out),
            lambda i: build_lesson_page(i, mistake_cap=args.mistakes, command=command),
            [lesson.id for lesson in LESSONS],
            inline=args.single_file,
            command=command,
            progress=lambda line: print(f"rtlab: {line}", file=sys.stderr),
            study=args.study,
        )
        print(f"rtlab: wrote {path} and the pages of {len(LESSONS)} lessons")
        return 0
    except UnknownLessonError as error:
        print(f"rtlab: error: {error}", file=sys.stderr)
        return 2
