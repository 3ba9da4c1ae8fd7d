"""``rtlab lesson list | show Lnn | student Lnn --out DIR [--from PREV] | grade DIR [--public]
[--report OUT] | check [--lesson Lnn] | autograder Lnn --out ZIP``: the verb's work (the
parser's entry lives in tracer/cli.py with the other verbs)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from lessons.catalog import LESSONS, UnknownLessonError, get_lesson
from lessons.grader import NoChecksError
from lessons.markers import MarkerError
from lessons.student import StudentTreeError, write_student_tree


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="lesson_command", required=True)
    sub.add_parser("list", help="the lessons in lecture order, with the concepts each checks")
    p = sub.add_parser("show", help="a lesson's text in the terminal")
    p.add_argument("lesson", help="a lesson id, e.g. L04")
    p = sub.add_parser("student", help="write a student's starting tree for a lesson")
    p.add_argument("lesson", help="a lesson id, e.g. L04")
    p.add_argument("--out", required=True, help="the directory to create (new or empty)")
    p.add_argument(
        "--from",
        dest="from_dir",
        help="an earlier tree of the student's: its code of the earlier lessons is carried over",
    )
    p = sub.add_parser("grade", help="grade a submission: probes of the lesson's concepts")
    p.add_argument("submission", help="a directory of C++ files named as in tracer/cpp/")
    p.add_argument(
        "--lesson", help="the lesson to grade (default: every lesson the submission's files touch)"
    )
    p.add_argument("--json", dest="json_path", help="write Gradescope's results.json here")
    p.add_argument(
        "--public",
        action="store_true",
        help="only the public checks (a student's self-check; the hidden variants count later)",
    )
    p.add_argument(
        "--no-scenes", action="store_true", help="probes only: no scene checks (quicker)"
    )
    p.add_argument(
        "--report",
        metavar="DIR",
        help="write a feedback page: DIR/index.html beside DIR/results.json and the images of "
        "the scenes that differ (DIR is replaced whole, only when grading finished)",
    )
    p.add_argument(
        "--single-file",
        action="store_true",
        help="with --report: the page's images inlined as data: URIs (one file to mail)",
    )
    p = sub.add_parser(
        "check",
        help="instructor: markers, stub trees, solution and known-wrong versions of every lesson",
    )
    p.add_argument("--lesson", help="only this lesson (default: every lesson with checks)")
    p.add_argument(
        "--no-scenes",
        action="store_true",
        help="grade the known-wrong versions on their probes only (quicker)",
    )
    p = sub.add_parser("autograder", help="instructor: the zip Gradescope takes for a lesson")
    p.add_argument("lesson", help="a lesson id, e.g. L04")
    p.add_argument("--out", required=True, help="the zip to write, e.g. autograder.zip")


def cmd_list() -> int:
    for lesson in LESSONS:
        print(f"{lesson.id}  {lesson.title}")
        print(f"     slide: {lesson.slide}")
        print(f"     writes: {lesson.writes}")
        print(f"     checks: {'; '.join(lesson.concepts)}")
    return 0


def cmd_show(lesson_id: str) -> int:
    lesson = get_lesson(lesson_id)
    if not lesson.text_path.exists():
        print(f"{lesson.id}: {lesson.title}\n\n(this lesson has no text yet)")
        return 0
    print(lesson.text_path.read_text(), end="")
    return 0


def cmd_student(lesson_id: str, out: str, from_dir: str | None) -> int:
    report = write_student_tree(lesson_id, Path(out), Path(from_dir) if from_dir else None)
    report.stubbed.sort(key=lambda r: (r.file, r.begin))
    names = ", ".join(
        f"{r.function}()" for r in report.stubbed if r.lesson == lesson_id and not r.is_copy
    )
    print(f"rtlab: wrote {out}: lesson {lesson_id}, you write {names}")
    later = sorted({r.lesson for r in report.stubbed if r.lesson != lesson_id})
    if later:
        print(f"rtlab: later lessons stubbed too: {', '.join(later)}")
    if report.carried:
        print(f"rtlab: carried your own code of {len(report.carried)} functions from {from_dir}")
        stubs = [r for r in report.carried if any("not_implemented(" in b for b in r.body)]
        for r in sorted(stubs, key=lambda r: (r.lesson, r.file, r.begin)):
            print(f"rtlab: warning: {r.function}() of {r.lesson} is still a stub in {r.file}")
    return 0


def cmd_grade(
    submission: str,
    lesson: str | None,
    json_path: str | None,
    public: bool = False,
    scenes: bool = True,
    report: str | None = None,
    single_file: bool = False,
) -> int:
    """Print the diagnosis and the score; write results.json (always, also for an empty or a
    broken submission) and the heat maps of failing scenes beside it; with `report`, the
    feedback page in that directory, beside its own results.json and the scenes' images.
    Exit status 0 whatever the score: grading worked."""
    from lessons.grader import grade

    if lesson is not None:
        lesson = get_lesson(lesson).id
    artifacts = Path(json_path).resolve().parent if json_path else None
    if artifacts is not None:
        artifacts.mkdir(parents=True, exist_ok=True)
    if report is None:
        result = grade(Path(submission), lesson, public=public, scenes=scenes,
                       artifacts=artifacts)  # fmt: skip
    else:
        import shlex
        import shutil

        from reports.feedback import artifact_names, feedback_page
        from reports.site import staged

        command = "rtlab " + " ".join(shlex.quote(a) for a in sys.argv[1:])
        with staged(Path(report)) as stage:  # a failed run leaves the old page as it was
            result = grade(Path(submission), lesson, public=public, scenes=scenes,
                           artifacts=stage)  # fmt: skip
            feedback_page(result, stage, command=command, inline=single_file)
        data = result.as_gradescope()
        if artifacts is not None and artifacts != Path(report).resolve():
            for name in artifact_names(data):  # the heat maps beside results.json, as ever
                if (Path(report) / name).is_file():
                    shutil.copyfile(Path(report) / name, artifacts / name)
    if json_path:
        result.write(json_path)
    print(result.diagnosis)
    for note in result.notes:
        print(f"note: {note}")
    print(
        f"rtlab: {', '.join(result.lessons)}: score {result.score:g} of {result.max_score:g} "
        f"({sum(t.status == 'passed' for t in result.tests)} of {len(result.tests)} checks pass)"
        + (f"; wrote {json_path}" if json_path else "")
        + (" (public checks only: the hidden variants count in the final grade)" if public else "")
    )
    if report is not None:
        print(f"rtlab: wrote the feedback page {Path(report) / 'index.html'}")
    return 0


def cmd_check(lesson: str | None, scenes: bool) -> int:
    """The instructor's check; exit status 1 on any failure."""
    from lessons.check import check_lessons, format_table
    from lessons.grader import lessons_with_checks

    chosen = [get_lesson(lesson).id] if lesson else lessons_with_checks()
    reports = check_lessons(chosen, scenes=scenes)
    print(format_table(reports))
    bad = [r.lesson for r in reports if not r.ok]
    print(f"rtlab: {len(reports) - len(bad)} of {len(reports)} lessons pass" +
          (f"; failing: {', '.join(bad)}" if bad else ""))  # fmt: skip
    return 1 if bad else 0


def cmd_autograder(lesson: str, out: str) -> int:
    from lessons.autograder import build_zip

    names = build_zip(get_lesson(lesson).id, Path(out))
    print(f"rtlab: wrote {out}: Gradescope's autograder for {lesson}, with {len(names)} "
          "scenes' references pre-rendered by POV-Ray and Mitsuba")  # fmt: skip
    return 0


def run(args: argparse.Namespace) -> int:
    """Exit status: 0 done; 2 bad input (an unknown lesson, an output that exists, bad markers)."""
    try:
        if args.lesson_command == "list":
            return cmd_list()
        if args.lesson_command == "show":
            return cmd_show(args.lesson)
        if args.lesson_command == "grade":
            if args.single_file and args.report is None:
                print("rtlab: error: --single-file inlines the feedback page's images: "
                      "give --report DIR too", file=sys.stderr)  # fmt: skip
                return 2
            return cmd_grade(
                args.submission,
                args.lesson,
                args.json_path,
                args.public,
                not args.no_scenes,
                args.report,
                args.single_file,
            )
        if args.lesson_command == "check":
            return cmd_check(args.lesson, not args.no_scenes)
        if args.lesson_command == "autograder":
            return cmd_autograder(args.lesson, args.out)
        return cmd_student(args.lesson, args.out, args.from_dir)
    except (UnknownLessonError, StudentTreeError, MarkerError, NoChecksError) as error:
        print(f"rtlab: error: {error}", file=sys.stderr)
        return 2
