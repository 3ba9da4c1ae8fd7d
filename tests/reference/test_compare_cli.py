"""rtlab convert / compare / bench, and the Mitsuba XML loading in a fresh process."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import tracer
from reference.bench import format_ratios, suite_classic
from reference.metrics import MITSUBA_TOLERANCE, agrees
from tests.helpers import ROOT, SCENES
from tracer.cli import main

SHADOWS = SCENES / "shadows.toml"


def test_convert_writes_povray_sdl(tmp_path, capsys):
    out = tmp_path / "s.pov"
    assert main(["convert", str(SHADOWS), "--to", "povray", "-o", str(out)]) == 0
    text = out.read_text()
    assert "#version 3.7;" in text and "max_trace_level 1" in text
    assert text.count("light_source") == 2 and text.count("sphere {") == 2
    assert "povray +I" in capsys.readouterr().out


@pytest.mark.parametrize("name", ["shadows", "torus_cylinder", "boxes_triangles"])
def test_mitsuba_xml_loads_in_a_fresh_process_and_renders_the_same(tmp_path, name):
    """The XML written by `convert` (with its meshes as PLY files beside it) loads with
    mi.load_file in any process that imported converters.mitsuba, and renders what the dict
    conversion renders."""
    source = SCENES / f"{name}.toml"
    xml = tmp_path / "s.xml"
    args = ["convert", str(source), "--to", "mitsuba", "-o", str(xml), "--quiet",
            "--width", "80", "--height", "60"]  # fmt: skip
    assert main(args) == 0
    npy = tmp_path / "xml.npy"
    code = (
        "import sys, numpy as np, mitsuba as mi, converters.mitsuba as cm\n"
        "cm.use_variant('llvm_ad_rgb')\n"
        f"img = mi.render(mi.load_file({str(xml)!r}))\n"
        f"np.save({str(npy)!r}, np.array(img))\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT, capture_output=True)
    from reference.mitsuba import run_mitsuba

    scene = tracer.load_scene(source).with_overrides(width=80, height=60)
    from_dict = run_mitsuba(scene, variant="llvm_ad_rgb", warm=False).image
    # Not bit for bit: the XML parser builds the camera transform from text in its own float32
    # steps. The same float32 argument as for any Mitsuba comparison applies.
    ok, text = agrees(from_dict, np.load(npy)[..., :3], MITSUBA_TOLERANCE)
    assert ok, text


@pytest.mark.parametrize("name", ["cornell_box", "path_glossy_mirror"])
def test_mitsuba_xml_of_a_path_scene_loads_in_a_fresh_process(tmp_path, name):
    """A path-traced scene's XML (Mitsuba's path integrator; rtlab's own glossy and mixed
    BSDF plugins in path_glossy_mirror) loads with mi.load_file in a fresh process that has
    only imported converters.mitsuba, and renders what the dict conversion renders: the same
    integrator, sampler and seed, so the same image up to float32 differences in how the XML
    parser builds transforms from text (measured: 7e-7 at most), within MITSUBA_TOLERANCE."""
    source = SCENES / f"{name}.toml"
    xml = tmp_path / "s.xml"
    args = ["convert", str(source), "--to", "mitsuba", "-o", str(xml), "--quiet",
            "--width", "32", "--height", "32", "--spp", "16"]  # fmt: skip
    assert main(args) == 0
    text = xml.read_text()
    assert '<integrator type="path">' in text
    if name == "path_glossy_mirror":
        assert 'type="rtlab_phong"' in text and 'type="rtlab_mixed_lobes"' in text
    npy = tmp_path / "xml.npy"
    code = (
        "import numpy as np, mitsuba as mi\n"
        "import converters.mitsuba  # registers rtlab's plugins in every variant\n"
        "mi.set_variant('llvm_ad_rgb')\n"
        f"img = mi.render(mi.load_file({str(xml)!r}))\n"
        f"np.save({str(npy)!r}, np.array(img))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    from reference.mitsuba import run_mitsuba

    scene = tracer.load_scene(source).with_overrides(width=32, height=32, spp=16)
    from_dict = run_mitsuba(scene, variant="llvm_ad_rgb", warm=False).image
    assert from_dict.std() > 0.02  # a picture, not a black square
    ok, text = agrees(from_dict, np.load(npy)[..., :3], MITSUBA_TOLERANCE)
    assert ok, text


def test_compare_writes_images_heat_maps_and_json(tmp_path, capsys):
    out = tmp_path / "cmp"
    js = tmp_path / "cmp" / "metrics.json"
    args = ["compare", str(SHADOWS), "--against", "povray,mitsuba", "--out-dir", str(out),
            "--json", str(js), "--width", "80", "--height", "60"]  # fmt: skip
    assert main(args) == 0
    table = capsys.readouterr().out
    assert "povray" in table and "mitsuba-llvm" in table and "SSIM" in table
    rows = json.loads(js.read_text())
    assert [r["renderer"] for r in rows] == ["rtlab", "povray", "mitsuba-llvm"]
    for r in rows[1:]:
        for key in ("rmse", "max_abs", "psnr", "ssim", "flip", "over_tolerance",
                    "trace_seconds", "whole_seconds"):  # fmt: skip
            assert key in r, key
        assert r["rmse"] < 1e-4 and r["ssim"] > 0.999 and r["over_tolerance"] <= 0.0005
        assert r["agrees"] is True, r["verdict"]
        assert Path(r["heat_map"]).exists()
    names = {p.name for p in out.iterdir()}
    assert {"shadows-rtlab.exr", "shadows-povray.png", "shadows-diff-mitsuba-llvm.png"} <= names


def mirror_the_povray_converter(monkeypatch) -> None:
    """A converter bug (the picture mirrored: ``right x`` for ``right -x``) in the SDL that
    compare and demo hand POV-Ray, checked to be injected."""
    import converters.povray

    def mirrored(scene, path):
        sdl = converters.povray.to_povray(scene)
        wrong = sdl.replace("right -x*", "right x*")
        assert wrong != sdl, "the bug was not injected"
        Path(path).write_text(wrong)
        return Path(path)

    monkeypatch.setattr("reference.povray.write_povray", mirrored)


def test_compare_exits_1_when_the_renderers_disagree(tmp_path, capsys, monkeypatch):
    """A converter bug (the picture mirrored: ``right x`` for ``right -x``) injected into the
    SDL that `rtlab compare` hands POV-Ray: the real POV-Ray renders it, the rule rejects it,
    and the exit status says so."""
    mirror_the_povray_converter(monkeypatch)
    js = tmp_path / "m.json"
    args = ["compare", str(SHADOWS), "--against", "povray", "--json", str(js),
            "--width", "80", "--height", "60", "--quiet"]  # fmt: skip
    assert main(args) == 1
    out, err = capsys.readouterr()
    assert "rtlab: povray disagrees with rtlab:" in err and "pixels" in err
    assert "exit status 1" in err
    assert next(ln for ln in out.splitlines() if ln.startswith("povray")).endswith("NO")
    row = json.loads(js.read_text())[1]
    assert (
        row["renderer"] == "povray"
        and row["agrees"] is False
        and "over tolerance" in row["verdict"]
    )


def test_demo_exits_1_when_the_renderers_disagree(tmp_path, capsys, monkeypatch):
    """`make demo` is a newcomer's first proof that the renderers agree: with the same mirrored
    converter injected, `rtlab demo` must say so in its exit status, as compare does."""
    mirror_the_povray_converter(monkeypatch)
    args = ["demo", "--out-dir", str(tmp_path), "--width", "96", "--height", "48", "--quiet"]
    assert main(args) == 1
    assert "rtlab: povray disagrees with rtlab:" in capsys.readouterr().err


def test_compare_gives_no_verdict_on_jittered_samples(capsys):
    """At spp > 1 each renderer jitters its own samples (and POV-Ray here takes one per pixel):
    no pixel rule applies, and compare says so rather than fail."""
    args = ["compare", str(SHADOWS), "--against", "povray", "--spp", "4", "--width", "40",
            "--height", "30", "--quiet"]  # fmt: skip
    assert main(args) == 0
    assert capsys.readouterr().out.splitlines()[-1].endswith("-")


def test_compare_help_states_the_exit_status(capsys):
    with pytest.raises(SystemExit):
        main(["compare", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "1 when one disagrees" in text and "130 or 143" in text


def test_compare_rejects_an_unknown_renderer(capsys):
    assert main(["compare", str(SHADOWS), "--against", "blender"]) == 2
    assert "unknown renderer 'blender'" in capsys.readouterr().err


def test_bench_rows_have_the_contract_fields():
    rows = suite_classic(repeats=1, threads=(1,), width=64, height=32)
    assert {r["renderer"] for r in rows} == {"rtlab", "povray", "mitsuba-llvm"}
    for r in rows:
        assert {"case", "renderer", "threads", "metric", "value", "unit"} <= set(r)
        assert r["metric"] == "seconds" and r["unit"] == "s" and r["value"] > 0
    for r in rows:
        r["machine"] = "test"
    text = format_ratios(rows)
    assert "ex25-64x32, 1 thread" in text and "rtlab is" in text


def test_bench_prints_each_renderers_gain_from_the_second_thread():
    from reference.bench import format_scaling, thread_scaling

    def row(renderer, threads, value, unit="s", case="ex25"):
        return {"suite": "classic", "case": case, "renderer": renderer, "threads": threads,
                "metric": "seconds" if unit == "s" else "mrays_per_s", "value": value,
                "unit": unit}  # fmt: skip

    rows = [row("rtlab", 1, 0.10), row("rtlab", 2, 0.05), row("povray", 1, 1.0),
            row("povray", 2, 0.8), row("rtlab", 1, 10.0, "Mrays/s", "bunny"),
            row("rtlab", 2, 19.0, "Mrays/s", "bunny"),
            row("embree", 1, 5.0, "Mrays/s", "bunny")]  # fmt: skip
    gains = thread_scaling(rows)
    # Times: 1-thread over 2-thread; throughputs: 2-thread over 1-thread; no pair, no entry.
    assert gains == {("classic", "ex25", "rtlab"): 2.0, ("classic", "ex25", "povray"): 1.25,
                     ("classic", "bunny", "rtlab"): 1.9}  # fmt: skip
    lines = format_scaling(rows)
    assert "classic: ex25, 1 -> 2 threads: rtlab 2.00x, povray 1.25x" in lines
    assert "classic: bunny, 1 -> 2 threads: rtlab 1.90x" in lines


def test_bench_markdown_gives_convergence_as_times_to_rtlabs_error():
    from reference.bench import format_markdown

    # RMSE = c / sqrt(seconds): rtlab's c is 1, the other's 2, so the other needs 4x the time
    # to any error; rtlab's median RMSE is 0.75, reached by rtlab in (1 / 0.75)^2 s.
    rows = [{"case": "box", "renderer": name, "threads": 2, "metric": "rmse", "unit": "",
             "value": c / t**0.5, "seconds": t, "machine": "m"}
            for name, c in (("rtlab", 1.0), ("other", 2.0)) for t in (1.0, 4.0)]  # fmt: skip
    table = format_markdown(rows, "rtlab bench convergence").splitlines()
    assert table[0] == "| case | threads | rtlab | other |"
    assert table[2] == "| box, time to RMSE 0.75 | 2 | 1.778 s | 7.111 s (rtlab 4.00x) |"


def test_bench_rows_name_the_cpu_and_its_vector_units():
    from reference.bench import cpu

    info = cpu()
    assert info["cpu_model"] and info["cpu_count"] >= 1
    # Every x86-64 has SSE2; the flags listed are the vector units' only.
    assert "sse2" in info["cpu_flags"] and "fpu" not in info["cpu_flags"]


def test_cpu_core_reads_the_flags_before_the_model_numbers():
    """The Xeon of this machine class reports Rocket Lake's numbers (family 6, model 167) with
    AMX, which only Sapphire Rapids and later Xeons have: its core is named by the flags."""
    from reference.bench import cpu_core

    intel = {"vendor_id": "GenuineIntel", "cpu family": "6", "model": "167"}
    assert cpu_core({**intel, "flags": "sse2 avx512f amx_tile avx512_fp16"}) == "sapphirerapids"
    assert cpu_core({**intel, "flags": "sse2 avx2 avx512f"}) == "rocketlake"
    assert cpu_core({**intel, "flags": "sse2 avx2"}) == ""  # no AVX-512: not one we name
    amd = {"vendor_id": "AuthenticAMD", "cpu family": "25", "flags": "avx512f"}
    assert cpu_core({**amd, "model": "17"}) == "znver4"  # EPYC Genoa, this class's Zen 4
    assert cpu_core({**amd, "model": "1"}) == "znver3"  # EPYC Milan
    assert cpu_core({**amd, "cpu family": "26", "model": "2"}) == "znver5"
    assert cpu_core({"vendor_id": "GenuineIntel", "flags": "sse2"}) == ""  # no numbers
    assert cpu_core({}) == ""


def test_bench_json_through_the_cli(tmp_path, capsys, monkeypatch):
    """`rtlab bench classic --json FILE` through main(), the suite made small (one repeat, one
    thread, 64x32): the JSON file holds the rows with the contract's fields, and the ratios
    are printed."""
    from functools import partial

    from reference.bench import SUITES, compiler

    small = partial(suite_classic, repeats=1, threads=(1,), width=64, height=32)
    monkeypatch.setitem(SUITES, "classic", small)
    js, md = tmp_path / "out" / "bench.json", tmp_path / "out" / "bench.md"
    assert main(["bench", "classic", "--json", str(js), "--markdown", str(md)]) == 0
    printed = capsys.readouterr().out
    assert "ex25-64x32, 1 thread (seconds):" in printed and f"rows in {js}" in printed
    # The compiler that built the core is named beside the CPU (its code's speed differs).
    built = compiler()
    assert f"core built by: {built}\n" in printed
    assert built.startswith("GCC ") or "clang" in built.lower(), built
    table = md.read_text().splitlines()
    assert table[0] == "| case | threads | rtlab | mitsuba-llvm | povray |"
    assert table[2].startswith("| ex25-64x32 | 1 | ") and table[2].count("(rtlab ") == 2
    assert f"Core built by {built}. Command: `rtlab bench classic --json {js}`." in table[-1]
    md.unlink()
    rows = json.loads(js.read_text())
    assert sorted(r["renderer"] for r in rows) == ["mitsuba-llvm", "povray", "rtlab"]
    for r in rows:
        assert r["case"] == "ex25-64x32" and r["threads"] == 1, r
        assert r["metric"] == "seconds" and r["unit"] == "s", r
        assert isinstance(r["value"], float) and r["value"] > 0, r
        assert r["suite"] == "classic" and r["machine"], r
        assert r["cpu_model"] and "sse2" in r["cpu_flags"] and "cpu_core" in r, r
        assert r["compiler"] == built, r
    assert [p.name for p in js.parent.iterdir()] == ["bench.json"]  # no temporary file left


def test_bench_refuses_an_unknown_suite(capsys):
    assert main(["bench", "fastest"]) == 2
    assert "unknown suite 'fastest'; expected all or classic, geometry" in capsys.readouterr().err


def test_geometry_bench_rows_have_the_contract_fields():
    from reference.bench import suite_geometry

    rows = suite_geometry(repeats=1, threads=(1,), width=64, height=32)
    primary = [r for r in rows if r["case"] == "bunny-primary"]
    assert {r["renderer"] for r in primary} == {"rtlab", "embree"}
    for r in primary:
        assert r["metric"] == "mrays_per_s" and r["value"] > 0 and r["threads"] == 1
    builds = [r for r in rows if r["case"] == "bunny-bvh-build"]
    assert {r["renderer"] for r in builds} == {"rtlab", "embree"}
    assert all(r["metric"] == "seconds" and r["value"] > 0 for r in builds)
    # Embree was timed on the work rtlab did: its answers (test below for the bound; the
    # camera's 2,048 rays here may differ on 2, where 5 of the 1920x1024 ones do).
    embree = [r for r in rows if r["renderer"] == "embree" and r["case"] != "bunny-bvh-build"]
    assert {r["case"] for r in embree} == {"bunny-primary", "bunny-diffuse"}
    assert all(r["agreement"] >= 0.999 for r in embree), embree


def test_embree_answers_the_diffuse_rays_as_rtlab_does():
    """bunny-diffuse times Embree on rtlab's rays in float32. Their origins lie 1e-14 off the
    surface (float64 error bounds); rounded to float32 (about 3e-6 steps on the bunny) half fall
    back onto it or below, and Embree hits the triangle they leave at t ~ 0: it would be timed
    on other work, with wrong answers. diffuse_rays_float32() offsets by float32's bound
    instead: every origin on Ng's side, and Embree finds rtlab's closest triangle (or none
    where rtlab finds none).
    The bound 0.999: on the bench's 2M rays 60 answers differ (99.997%): rays whose nearest hit
    lies within the float32 offset of their origin, ties at an edge two triangles share (each
    search may keep either), and Embree's non-watertight test letting a ray through an edge; at
    that rate 20,000 rays have 0.6 differing on average, and 20 (the bound) are out of reach.
    Merely rounded origins agree on about half, which the last assertion shows this test sees."""
    import dataclasses

    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    from reference.bench import _surface_samples, agreement, diffuse_rays, diffuse_rays_float32
    from tracer import _core
    from tracer.render import to_core
    from tracer.scene import Mesh, load_scene

    scene = load_scene(ROOT / "reference" / "scenes" / "bunny.toml")
    meshes = tuple(o for o in scene.objects if isinstance(o, Mesh))
    mesh = meshes[0]
    n, seed = 20_000, 4
    origins, directions = diffuse_rays(mesh.vertices, mesh.faces, n, seed)
    origins32, directions32 = diffuse_rays_float32(mesh.vertices, mesh.faces, n, seed)
    p, _, ng, d = _surface_samples(mesh.vertices, mesh.faces, n, seed)
    assert origins32.dtype == directions32.dtype == np.float32
    assert np.array_equal(directions32, d.astype(np.float32))
    # Each float32 origin strictly on Ng's side of its point (float64 arithmetic, exact enough:
    # the offsets are about 2e-5, the products' roundings 1e-14).
    assert np.all(np.sum((origins32.astype(np.float64) - p) * ng, axis=1) > 0)

    core = to_core(dataclasses.replace(scene, objects=meshes))
    ours = _core.closest_mesh_hits(core, origins, directions, 1)[2]
    embree = rtcore_scene.EmbreeScene(robust=False)
    TriangleMesh(embree, np.ascontiguousarray(mesh.vertices[mesh.faces], dtype=np.float32))
    fair = embree.run(origins32, directions32, query="INTERSECT", output=1)["primID"]
    assert agreement(ours, fair) >= 0.999
    naive = embree.run(
        origins.astype(np.float32), directions.astype(np.float32), query="INTERSECT", output=1
    )["primID"]
    assert agreement(ours, naive) < 0.8


def test_convergence_rows_plot_and_summary(tmp_path):
    from reference.convergence import convergence, plot, summary, time_to_error

    rows = convergence(width=32, height=32, sweep=(4, 16), renderers=("rtlab", "mitsuba-llvm"))
    assert {r["renderer"] for r in rows} == {"rtlab", "mitsuba-llvm"}
    for r in rows:
        assert "cornell" in r["case"] and r["metric"] == "rmse"
        assert r["value"] > 0 and r["seconds"] > 0 and r["spp"] in (4, 16)
        assert {"relmse", "flip", "threads", "unit"} <= set(r)
    # More samples, less error: Monte Carlo (16 vs 4 spp halves the RMSE in expectation).
    for name in ("rtlab", "mitsuba-llvm"):
        err = {r["spp"]: r["value"] for r in rows if r["renderer"] == name}
        assert err[16] < 0.8 * err[4]
    plot(rows, tmp_path / "c.png")
    assert (tmp_path / "c.png").stat().st_size > 1000
    assert "rtlab is" in summary(rows)
    assert all(t > 0 for t in time_to_error(rows, 0.05).values())


def test_classic_convergence_includes_povray():
    from reference.convergence import convergence_classic

    rows = convergence_classic(width=24, height=18, sweep=(1, 3), reference_spp=64)
    assert {r["renderer"] for r in rows} == {"rtlab", "povray", "mitsuba-llvm"}
    for name in ("rtlab", "povray"):
        err = {r["spp"]: r["value"] for r in rows if r["renderer"] == name}
        assert err[9] < err[1]  # antialiasing converges toward the reference


def test_povray_refuses_path_scenes(tmp_path, capsys):
    cornell = SCENES / "cornell_box.toml"
    assert main(["convert", str(cornell), "--to", "povray", "-o", str(tmp_path / "c.pov")]) == 2
    assert "POV-Ray reproduces the classic model only" in capsys.readouterr().err
    assert main(["compare", str(cornell), "--against", "povray"]) == 2
    assert not (tmp_path / "c.pov").exists()


def test_usage_errors_suggest_the_near_name_and_are_not_scene_errors(capsys):
    from tracer.cli import UsageError
    from tracer.scene import SceneError

    assert not issubclass(UsageError, SceneError)  # a command line is not a scene
    assert main(["compare", str(SHADOWS), "--against", "povrya"]) == 2
    assert "(did you mean 'povray'?)" in capsys.readouterr().err
    assert main(["bench", "geometri"]) == 2
    assert "(did you mean 'geometry'?)" in capsys.readouterr().err


def test_a_case_with_several_metrics_names_each_on_its_row():
    """The viewer's and the batch's rows have several metrics per case; a table or a scaling
    line that left the metric out would show four numbers for one case with nothing to tell
    them apart, and the scaling line would report whichever metric came last."""
    from reference.bench import format_markdown, thread_scaling

    base = {"case": "view", "renderer": "rtlab", "machine": "test CPU", "suite": "viewer"}
    rows = [
        base | {"threads": 1, "metric": "render_ms", "value": 80.0, "unit": "ms"},
        base | {"threads": 2, "metric": "render_ms", "value": 40.0, "unit": "ms"},
        base | {"threads": 1, "metric": "fps", "value": 8.0, "unit": "frames/s"},
        base | {"threads": 2, "metric": "fps", "value": 12.0, "unit": "frames/s"},
        base | {"threads": 1, "metric": "frame_bytes", "value": 9e4, "unit": "bytes"},
        base | {"threads": 2, "metric": "frame_bytes", "value": 9e4, "unit": "bytes"},
    ]
    gains = thread_scaling(rows)
    # A time halves (2x), a rate grows 1.5x; a frame's size has no gain from a thread.
    assert gains == {("viewer", "view, render_ms", "rtlab"): 2.0,
                     ("viewer", "view, fps", "rtlab"): 1.5}  # fmt: skip
    table = format_markdown(rows, "rtlab bench viewer").splitlines()
    assert table[0] == "| case | threads | rtlab |"
    assert "| view, render_ms | 2 | 40 ms |" in table
    assert "| view, fps | 1 | 8 frames/s |" in table
    # Without rtlab rows (the batch suite's engines) there is no empty rtlab column.
    engines = [r | {"renderer": "serial", "case": "grade"} for r in rows[:2]]
    assert format_markdown(engines).splitlines()[0] == "| case | threads | serial |"
