"""``rtlab lesson list | show Lnn | student Lnn --out DIR [--from PREV] | grade DIR [--public]
[--report OUT] | grade DIR... --out GRADES [--workers N | --scheduler ADDR] | references --all
| check [--lesson Lnn] | autograder Lnn --out ZIP``: the verb's work (the parser's entry lives
in tracer/cli.py with the other verbs). The batches (a class, every lesson's references) go
through tracer/batch.py."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from lessons.catalog import LESSONS, UnknownLessonError, get_lesson
from lessons.grader import NoChecksError
from lessons.markers import MarkerError
from lessons.student import StudentTreeError, write_student_tree
from tracer.batch import BatchError, add_engine_arguments


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
    p = sub.add_parser(
        "grade",
        help="grade a submission: probes of the lesson's concepts; several (a class) with --out",
    )
    p.add_argument(
        "submission",
        nargs="+",
        help="a directory of C++ files named as in tracer/cpp/; with --out, any number of them",
    )
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
    p.add_argument(
        "--out",
        metavar="GRADES",
        help="a class: each submission's results.json in GRADES/<its name>/, a summary in "
        "GRADES/summary.json and summary.txt, timings in GRADES/timings.json; graded as a "
        "batch (tracer/batch.py: --workers, --scheduler); a submission graded before, "
        "unchanged, is skipped",
    )
    add_engine_arguments(p)
    p = sub.add_parser(
        "references",
        help="render the lessons' POV-Ray and Mitsuba references into their cache, as a batch",
    )
    p.add_argument("--all", action="store_true", help="every lesson's scenes (and Ex 25's)")
    p.add_argument("--lesson", help="only this lesson's scenes")
    add_engine_arguments(p)
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


# --- batches: a class, the references (tracer/batch.py) ------------------------------------


def class_tasks(
    submissions: list[Path], lesson: str | None, out: Path, public: bool, scenes: bool
) -> list[Any]:
    """One task per submission: graded into out/<its directory's name>/, keyed by the
    submission's files, the options and the grader's sources."""
    from lessons.grader import GRADER_SOURCES, grade_into
    from lessons.scene_checks import ROOT
    from lessons.student import _submitted_files
    from tracer.batch import DONE, BatchError, Task, digest, sources_digest

    names: dict[str, Path] = {}
    for path in submissions:
        name = path.resolve().name
        if name in names:
            raise BatchError(
                f"{names[name]} and {path}: two submissions named {name!r}; each is graded "
                f"into --out/<its directory's name>/"
            )
        names[name] = path
    grader = sources_digest(ROOT, GRADER_SOURCES)
    tasks = []
    for name, path in names.items():
        files = list(_submitted_files(path).values()) if path.is_dir() else []
        key = digest(lesson, public, scenes, grader, files=files)
        args = (str(path.resolve()), lesson, str((out / name).resolve()), public, scenes)
        tasks.append(Task(name, grade_into, args, (out / name / DONE).resolve(), key))
    return tasks


def class_summary(lesson: str | None, outcomes: list[Any]) -> dict[str, Any]:
    """The class's summary: per submission (in name order) its score, the diagnosis's first
    line and its faults, or why its task failed. No timing: the same on every engine."""
    rows = []
    for o in sorted(outcomes, key=lambda o: o.name):
        row: dict[str, Any] = {"name": o.name}
        if o.status == "error":
            row |= {"status": "error", "reason": o.reason}
        else:
            row |= {"status": "failed" if o.reason else "graded", **o.data}
            if o.reason:
                row["reason"] = o.reason
        rows.append(row)
    return {"lesson": lesson, "submissions": rows}


def format_class_table(summary: dict[str, Any]) -> str:
    rows = summary["submissions"]
    scores = [f"{r['score']:g} / {r['max_score']:g}" if "score" in r else "-" for r in rows]
    width = max([len("submission"), *(len(r["name"]) for r in rows)])
    wide = max([len("score"), *(len(s) for s in scores)])
    lines = [f"{'submission':<{width}}  {'score':>{wide}}  {'status':<7}  diagnosis"]
    for r, score in zip(rows, scores, strict=True):
        said = r.get("diagnosis") or r.get("reason", "")
        lines.append(f"{r['name']:<{width}}  {score:>{wide}}  {r['status']:<7}  {said[:90]}")
    return "\n".join(lines) + "\n"


def cmd_grade_class(
    submissions: list[str], lesson: str | None, out: str, public: bool, scenes: bool, engine: Any
) -> int:
    """A class as a batch. Exit status 0 when every submission was graded (whatever it
    scored, and also when it crashed: its results.json says so), 1 when a task itself failed
    (the grader's fault or the cluster's: the summary says which and why)."""
    from tracer.batch import run_batch, summary, write_atomic, write_timings

    if lesson is not None:
        lesson = get_lesson(lesson).id
    grades = Path(out)
    if grades.exists() and not grades.is_dir():
        print(f"rtlab: error: --out: {out} is a file; expected a directory", file=sys.stderr)
        return 2
    tasks = class_tasks([Path(s) for s in submissions], lesson, grades, public, scenes)
    print(f"rtlab: grading {len(tasks)} submissions on {engine.describe()}", file=sys.stderr)
    outcomes = run_batch(tasks, engine, desc=f"grading {lesson or 'submissions'}")
    data = class_summary(lesson, outcomes)
    write_atomic(grades / "summary.json", json.dumps(data, indent=1) + "\n")
    table = format_class_table(data)
    write_atomic(grades / "summary.txt", table)
    write_timings(grades / "timings.json", outcomes, engine)
    print(table, end="")
    print(summary(outcomes, "submissions"))
    print(f"rtlab: wrote {grades / 'summary.json'}, {grades / 'summary.txt'} and each "
          f"submission's results.json in {grades}/<name>/")  # fmt: skip
    return 1 if any(o.status == "error" for o in outcomes) else 0


def reference_checks(lesson: str | None) -> list[Any]:
    """The scene checks whose references a lesson's grading reads: each lesson's scenes (or
    one lesson's), and the integration check's Ex 25 (with every lesson)."""
    from lessons.grader import INTEGRATION_SCENE, lessons_with_checks
    from lessons.scene_checks import lesson_scenes

    chosen = [get_lesson(lesson).id] if lesson else lessons_with_checks()
    checks = [c for each in chosen for c in lesson_scenes(each)]
    return checks if lesson else [*checks, INTEGRATION_SCENE]


def render_reference(lesson: str, name: str, directory: str) -> dict[str, Any]:
    """One task: one scene's POV-Ray and Mitsuba references into the cache `directory`
    (lessons/scene_checks.py references(): keyed, written atomically, under a lock)."""
    import os

    from lessons.scene_checks import reference_file, references

    check = next(c for c in reference_checks(None if lesson == "integration" else lesson)
                 if c.lesson == lesson and c.name == name)  # fmt: skip
    before = os.environ.get("RTLAB_REFERENCES")
    os.environ["RTLAB_REFERENCES"] = directory  # the worker's cache is the client's
    try:
        images = references(check)
        return {"file": reference_file(check).name, "arrays": sorted(images)}
    finally:  # a worker's later tasks see its own environment again
        if before is None:
            os.environ.pop("RTLAB_REFERENCES", None)
        else:
            os.environ["RTLAB_REFERENCES"] = before


def cmd_references(lesson: str | None, every: bool, engine: Any) -> int:
    from lessons.scene_checks import reference_dir, reference_file, reference_key
    from tracer.batch import Task, run_batch, summary

    if not every and lesson is None:
        print("rtlab: error: lesson references: give --all (every lesson) or --lesson Lnn",
              file=sys.stderr)  # fmt: skip
        return 2
    directory = reference_dir().resolve()
    tasks = []
    for check in reference_checks(lesson):
        done = reference_file(check).with_suffix(".done.json").resolve()
        tasks.append(Task(f"{check.lesson}-{check.name}", render_reference,
                          (check.lesson, check.name, str(directory)), done,
                          reference_key(check)))  # fmt: skip
    print(f"rtlab: rendering {len(tasks)} scenes' references into {directory} on "
          f"{engine.describe()}", file=sys.stderr)  # fmt: skip
    outcomes = run_batch(tasks, engine, desc="references")
    print(summary(outcomes, "scenes"))
    return 1 if any(o.status in ("failed", "error") for o in outcomes) else 0


def run(args: argparse.Namespace) -> int:
    """Exit status: 0 done; 2 bad input (an unknown lesson, an output that exists, bad markers)."""
    try:
        if args.lesson_command == "list":
            return cmd_list()
        if args.lesson_command == "show":
            return cmd_show(args.lesson)
        if args.lesson_command == "references":
            from tracer.batch import engine_from

            return cmd_references(args.lesson, args.all, engine_from(args))
        batch = args.lesson_command == "grade" and (
            args.out is not None
            or len(args.submission) > 1
            or args.workers is not None
            or args.scheduler is not None
        )
        if batch:
            from tracer.batch import engine_from

            if args.out is None:
                print("rtlab: error: grading a class (several submissions, --workers, "
                      "--scheduler) writes a directory of results: give --out GRADES",
                      file=sys.stderr)  # fmt: skip
                return 2
            if args.json_path or args.report:
                print("rtlab: error: --out grades a class: each results.json goes to "
                      "GRADES/<name>/; --json and --report are for one submission",
                      file=sys.stderr)  # fmt: skip
                return 2
            return cmd_grade_class(args.submission, args.lesson, args.out, args.public,
                                   not args.no_scenes, engine_from(args))  # fmt: skip
        if args.lesson_command == "grade":
            if args.single_file and args.report is None:
                print("rtlab: error: --single-file inlines the feedback page's images: "
                      "give --report DIR too", file=sys.stderr)  # fmt: skip
                return 2
            return cmd_grade(
                args.submission[0],
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
    except (UnknownLessonError, StudentTreeError, MarkerError, NoChecksError, BatchError) as error:
        print(f"rtlab: error: {error}", file=sys.stderr)
        return 2
