"""ident.daisy: the manifest, the loaders, where the files come from, the download (against a local
HTTP server, never the internet) and a smoke test of the Section 4 runner."""
from __future__ import annotations

import concurrent.futures
import contextlib
import csv
import dataclasses
import functools
import gzip
import http.server
import io
import json
import re
import shutil
import signal
import socket
import sys
import time
import tracemalloc
import zlib
from pathlib import Path

import numpy as np
import pytest

from conftest import local_http_server
from ident import daisy, daisy_report, daisy_runner

SHARED = Path(__file__).resolve().parents[2] / "shared" / "daisy"
XDG_ONLY = pytest.mark.skipif(sys.platform in ("win32", "darwin"), reason="the XDG cache convention is for Linux/Unix")


@pytest.fixture
def shared() -> Path:
    if not (SHARED / "datasets.toml").is_file():
        pytest.skip(f"the DAISY files are not in {SHARED} (the project's shared folder beside the repository)")
    return SHARED


@pytest.fixture
def no_environment(monkeypatch, tmp_path):
    """No IDENT_DAISY_* variables, and a private cache directory."""
    monkeypatch.delenv(daisy.DIRECTORY_VARIABLE, raising=False)
    monkeypatch.delenv(daisy.URL_VARIABLE, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg-cache"))
    return tmp_path


# --- the manifest ------------------------------------------------------------------------------------

def test_best_peer_fits_equal_the_reference_file():
    peers = Path(__file__).resolve().parents[1] / "reference" / "peers.md"
    if not peers.is_file():
        pytest.skip(f"{peers} is not there")
    best = {}
    for line in peers.read_text(encoding="utf-8").splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if len(cells) > 3 and cells[0].isdigit():
            best[cells[1]] = float(cells[-1])
    assert best == daisy_runner.PEER_BEST_FIT


def test_manifest_equals_the_toml_file(shared):
    tomllib = pytest.importorskip("tomllib")
    manifest = tomllib.loads((shared / "datasets.toml").read_text(encoding="utf-8"))
    assert list(manifest) == list(daisy.MANIFEST)
    for name, entry in manifest.items():
        ours = dataclasses.asdict(daisy.MANIFEST[name])
        for key, value in entry.items():
            if key in ("inputs", "outputs", "step_responses"):
                value = tuple(int(x) for x in value.split(":"))
            assert ours[key] == value, (name, key)
        for key, value in ours.items():
            if key not in entry and key not in ("name", "note"):
                assert value is None, (name, key)


def test_table1_lists_the_17_sets_in_order():
    sets = daisy.table1()
    assert [d.table for d in sets] == list(range(1, 18))
    assert sets[0].name == "erie" and sets[-1].name == "steamgen"
    assert len(daisy.datasets()) == 18 and daisy.datasets()[-1].name == "distill2"


def test_unknown_data_set_names_the_known_ones():
    with pytest.raises(ValueError, match="unknown DAISY data set 'nope'.*robot_arm"):
        daisy.dataset("nope")
    with pytest.raises(TypeError, match="name must be"):
        daisy.dataset(3)


# --- loading -----------------------------------------------------------------------------------------

def test_every_table1_set_loads_with_its_shape(shared):
    for d in daisy.table1():
        u, y = daisy.load(d.name, shared, download_missing=False)
        assert u.shape == (d.T, d.m) and y.shape == (d.T, d.p), d.name
        assert np.all(np.isfinite(u)) and np.all(np.isfinite(y))


def test_load_picks_the_columns_of_the_manifest(shared):
    table = np.loadtxt(shared / "erie.dat")
    u, y = daisy.load("erie", shared)
    assert np.array_equal(u, table[:, 1:6]) and np.array_equal(y, table[:, 21:23])


def test_step_responses_of_distill2(shared):
    u, y = daisy.load_step_responses("distill2", shared)
    table = np.loadtxt(shared / "distill2.dat")
    assert u.shape == (251, 3, 3) and y.shape == (251, 2, 3)
    for i in range(3):
        assert np.array_equal(y[:, :, i], table[:, 2 * i + 1: 2 * i + 3])
        assert np.all(u[:, i, i] == 1) and np.all(np.delete(u[:, :, i], i, axis=1) == 0)
    w = np.concatenate([u, y], axis=1)
    assert w.shape == (251, 5, 3)  # T x q x N, the form ident takes


def test_loaders_refuse_the_other_kind_of_set(shared):
    with pytest.raises(ValueError, match="load_step_responses"):
        daisy.load("distill2", shared)
    with pytest.raises(ValueError, match="no step responses"):
        daisy.load_step_responses("erie", shared)


# --- where the files come from -----------------------------------------------------------------------

@XDG_ONLY
def test_directory_precedence(no_environment, monkeypatch, tmp_path):
    assert daisy.data_directory() == tmp_path / "xdg-cache" / "ident" / "daisy"
    monkeypatch.setenv(daisy.DIRECTORY_VARIABLE, str(tmp_path / "from-env"))
    assert daisy.data_directory() == tmp_path / "from-env"
    assert daisy.data_directory(tmp_path / "given") == tmp_path / "given"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.delenv(daisy.DIRECTORY_VARIABLE)
    assert daisy.data_directory() == Path.home() / ".cache" / "ident" / "daisy"


def test_url_precedence(no_environment, monkeypatch):
    assert daisy.base_url() == daisy.DEFAULT_URL
    monkeypatch.setenv(daisy.URL_VARIABLE, "http://mirror.example/daisy")
    assert daisy.base_url() == "http://mirror.example/daisy/"
    assert daisy.base_url("http://given/") == "http://given/"


def test_load_reads_the_directory_of_the_environment_variable(shared, no_environment, monkeypatch):
    monkeypatch.setenv(daisy.DIRECTORY_VARIABLE, str(shared))
    u, y = daisy.load("robot_arm", download_missing=False)
    assert u.shape == (1024, 1)


def test_a_modified_local_file_is_refused(shared, no_environment, tmp_path):
    folder = tmp_path / "data"
    folder.mkdir()
    (folder / "erie.dat").write_bytes((shared / "erie.dat").read_bytes() + b"\n1 2 3\n")
    with pytest.raises(daisy.ChecksumError, match="erie.dat.*IDENT_DAISY_DIR"):
        daisy.load("erie", folder)


def test_a_missing_file_without_download_says_what_to_do(no_environment, tmp_path):
    with pytest.raises(daisy.DataNotFoundError, match="erie.dat is not in .*DAISY database.*IDENT_DAISY_DIR"):
        daisy.data_file("erie", tmp_path / "empty", download_missing=False)


# --- the download, against a local server -------------------------------------------------------------

class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


@contextlib.contextmanager
def _serving(root: Path):
    with local_http_server(functools.partial(_QuietHandler, directory=str(root))) as port:
        yield f"http://127.0.0.1:{port}/"


def _publish(root: Path, name: str, content: bytes) -> None:
    """Put `content` where the manifest's path of `name` points, gzip-compressed like DAISY's server."""
    target = root / daisy.dataset(name).path
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_bytes(gzip.compress(content))


@pytest.fixture
def server(shared, tmp_path):
    root = tmp_path / "server"
    _publish(root, "erie", (shared / "erie.dat").read_bytes())
    _publish(root, "robot_arm", (shared / "robot_arm.dat").read_bytes()[:-200])  # corrupted: truncated
    with _serving(root) as url:
        yield url


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir()) if folder.exists() else []


def test_download_of_a_good_file(server, shared, no_environment, tmp_path):
    cache = tmp_path / "cache"
    path = daisy.data_file("erie", cache, url=server)
    assert path == cache / "erie.dat"
    assert path.read_bytes() == (shared / "erie.dat").read_bytes()
    assert _leftovers(cache) == ["erie.dat"]  # no temporary file left
    u, y = daisy.load("erie", cache, url="http://127.0.0.1:9/never-used/")  # now cached: no download
    assert u.shape == (57, 5)


@XDG_ONLY
def test_download_uses_the_url_variable_and_the_default_cache(server, no_environment, monkeypatch, tmp_path):
    monkeypatch.setenv(daisy.URL_VARIABLE, server)
    path = daisy.data_file("erie")
    assert path == tmp_path / "xdg-cache" / "ident" / "daisy" / "erie.dat" and path.is_file()


def test_download_of_a_corrupted_file_leaves_nothing(server, no_environment, tmp_path):
    cache = tmp_path / "cache"
    with pytest.raises(daisy.ChecksumError, match="downloaded from .*robot_arm.dat.gz.*IDENT_DAISY_DIR"):
        daisy.data_file("robot_arm", cache, url=server)
    assert _leftovers(cache) == []


def test_download_of_a_missing_file_leaves_nothing(server, no_environment, tmp_path):
    cache = tmp_path / "cache"
    with pytest.raises(daisy.DownloadError, match="could not download .*flutter.dat.gz: HTTP 404.*IDENT_DAISY_DIR"):
        daisy.data_file("flutter", cache, url=server)
    assert _leftovers(cache) == []


def test_download_from_a_server_that_is_down(no_environment, tmp_path):
    with socket.socket() as probe:  # a port that was free a moment ago and is closed now
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    cache = tmp_path / "cache"
    with pytest.raises(daisy.DownloadError, match=f"could not download http://127.0.0.1:{port}/.*IDENT_DAISY_DIR"):
        daisy.download("erie", cache, url=f"http://127.0.0.1:{port}/", timeout=5)
    assert _leftovers(cache) == []


def test_an_interrupted_download_leaves_nothing(server, no_environment, monkeypatch, tmp_path):
    def failing_replace(source, target):
        raise OSError("disk full")

    monkeypatch.setattr(daisy.os, "replace", failing_replace)
    cache = tmp_path / "cache"
    with pytest.raises(OSError, match="disk full"):
        daisy.data_file("erie", cache, url=server)
    assert _leftovers(cache) == []


def test_an_uncompressed_mirror_works_too(shared, no_environment, tmp_path):
    root = tmp_path / "plain"
    target = root / daisy.dataset("erie").path
    target.parent.mkdir(parents=True)
    shutil.copy(shared / "erie.dat", target)  # served as is, without gzip
    with _serving(root) as url:
        assert daisy.data_file("erie", tmp_path / "cache", url=url).is_file()


# --- the runner ----------------------------------------------------------------------------------------

def test_runner_on_two_small_sets(shared, tmp_path):
    progress = io.StringIO()
    results = daisy_runner.run_benchmark(["erie", "robot_arm"], directory=shared, download_missing=False,
                                  progress=progress)
    assert [r.name for r in results] == ["erie", "robot_arm"]
    assert "2/2 robot_arm" in progress.getvalue()
    erie, robot_arm = results
    assert (erie.n_identification, erie.n_validation) == (40, 17)
    for mode in ("oe", "eiv"):
        assert robot_arm.modes[mode].fit > 90, mode
        # ident's default starts, every one reported with the validation of its model
        assert [c.start for c in robot_arm.modes[mode].candidates] == ["lra", "arx", "subspace"]
        assert all(c.validation.mean_fit > 0 for c in robot_arm.modes[mode].candidates)
    lra = erie.modes["eiv"].candidates[0]
    assert lra.start == "lra" and lra.misfit <= daisy_runner.REFERENCE_MISFIT["erie"] * (1 + 1e-6)
    assert erie.peer_fit == 38.1
    paths = daisy_report.write_results(results, tmp_path / "out")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["figure1.png", "results.json", "run-log.json",
                                                                    "table.csv", "table.md"]
    table = paths["markdown"].read_text()
    assert "| 8 | robot_arm | 1024 | 1 | 1 | 4 |" in table and "original software" in table
    document = json.loads(paths["json"].read_text())
    assert document["sets"][1]["modes"]["oe"]["fit"] > 90 and document["reference"]["mean_fit"]["oe"] == 35.2
    rows = list(csv.DictReader(paths["csv"].open()))
    assert [row["set"] for row in rows] == ["erie", "robot_arm"] and float(rows[1]["eiv_fit"]) > 90


def test_results_read_back_give_the_same_files(shared, tmp_path):
    # load_results is write_results read backwards: the files drawn again from results.json are the same
    results = daisy_runner.run_benchmark(["erie", "robot_arm"], directory=shared, download_missing=False,
                                         progress=None)
    first = daisy_report.write_results(results, tmp_path / "a", settings={"init": "auto"})
    loaded = daisy_report.load_results(first["json"])
    assert [r.name for r in loaded] == ["erie", "robot_arm"]
    assert loaded[1].modes["eiv"].candidates[2].start == "subspace"
    assert loaded[1].modes["eiv"].candidates[2].fit == results[1].modes["eiv"].candidates[2].fit
    again = daisy_report.write_results(loaded, tmp_path / "b", settings={"init": "auto"})
    for key in ("markdown", "csv", "json", "figure"):
        assert first[key].read_bytes() == again[key].read_bytes(), key


def test_committed_results_hold_no_date_version_or_time_and_repeat_byte_for_byte(shared, tmp_path):
    # the four files of a run go into docs/ and are committed: the same data and code must give the same
    # bytes; the date, the versions and the seconds go to the run log only
    results = daisy_runner.run_benchmark(["robot_arm"], directory=shared, download_missing=False, progress=None)
    first = daisy_report.write_results(results, tmp_path / "a")
    again = daisy_runner.run_benchmark(["robot_arm"], directory=shared, download_missing=False, progress=None)
    second = daisy_report.write_results(again, tmp_path / "b")
    for key in ("markdown", "csv", "json"):
        text = first[key].read_text()
        assert text == second[key].read_text(), key
        assert "seconds" not in text and "Generated" not in text and "numpy" not in text, key
        assert not re.search(r"20\d\d-\d\d-\d\d", text), key
    assert first["figure"].read_bytes() == second["figure"].read_bytes()
    log = json.loads(first["log"].read_text())
    assert log["seconds"]["robot_arm"]["eiv"]["all starts"] > 0 and log["versions"]["numpy"]
    ignored = (Path(__file__).resolve().parents[1] / ".gitignore").read_text().split()
    assert daisy_report.RUN_LOG in ignored


def _rounded(value, kind, digits):
    if value is None or digits is None or (kind == "significant" and value == 0):
        return value
    return round(value, daisy_runner.decimal_places(value, kind, digits))


def test_results_hold_no_iterations_or_seconds_and_numbers_at_the_printed_digits(shared, tmp_path):
    # issue 27: the committed files are the same on every machine, so they hold no iteration count or time,
    # and every number is rounded to the digits printed (fewer, or none, where the run and its replays differ)
    results = daisy_runner.run_benchmark(["erie", "robot_arm"], directory=shared, download_missing=False,
                                         progress=None)
    paths = daisy_report.write_results(results, tmp_path)
    assert "| iter |" not in paths["markdown"].read_text()
    assert '"iterations"' not in paths["json"].read_text() and '"seconds"' not in paths["json"].read_text()
    assert not any("iterations" in name or "seconds" in name for name in paths["csv"].read_text().splitlines()[0].split(","))
    document = json.loads(paths["json"].read_text())
    assert document["settings"]["refine"] == daisy_runner.REFINE and document["settings"]["replays"] >= 1
    assert all(round(v, 1) == v for v in document["mean_fit"].values())
    checked = 0
    for entry in document["sets"]:
        for mode in entry["modes"].values():
            numbers = [(mode, daisy_runner.DIGITS)] + [(c, daisy_runner.CANDIDATE_DIGITS) for c in mode["candidates"]
                                                         if "error" not in c]
            for number, table in numbers:
                assert "iterations" not in number and "seconds" not in number
                for field, digits in table.items():
                    kept = number["digits"].get(field, digits.standard)
                    values = number[field] if isinstance(number[field], list) else [number[field]]
                    kept = kept if isinstance(kept, list) else [kept] * len(values)
                    for value, places in zip(values, kept):
                        assert places in (digits.standard, digits.flat), (entry["name"], field)
                        assert value == _rounded(value, digits.kind, places), (entry["name"], field)
                        checked += 1
    assert checked > 50
    log = json.loads(paths["log"].read_text())
    assert log["iterations"]["robot_arm"]["eiv"]["kept"] > 0 and log["seconds"]["robot_arm"]["eiv"]["replays"] > 0
    assert len(log["samples"]["robot_arm"]["eiv"]) == 1 + daisy_runner.REPLAYS
    # the table prints the rounded numbers with their digits, and names the flat valleys
    table = paths["markdown"].read_text()
    robot = results[1].modes["eiv"]
    assert not robot.flat_valley and f"| {daisy_report.shown(robot, 'misfit')} | lra | 96.8 |" in table
    for name in daisy_report.flat_valleys(results):
        assert name in table.split("Flat valleys")[1]


def test_the_digits_printed():
    chosen = daisy_runner.representative

    def run(misfit, fit, start="lra"):
        return {"misfit": misfit, "fit": fit, "start": start}
    # the run and its replays agree: the run's numbers with the standard digits
    assert chosen([run(2.5, 63.8467), run(2.5 * (1 + 1e-12), 63.8467 + 1e-9), run(2.5, 63.8468)]) == 0
    # in a flat valley (no two agree to rounding) None: the flat digits
    assert chosen([run(1149438.1, 63.847), run(1149438.3, 63.854), run(1149438.2, 63.851)]) is None
    assert chosen([run(837.986, 48.46), run(837.979, 48.46), run(837.991, 48.46)]) is None
    assert chosen([run(2.5, 1.0), run(2.5, 1.0, "arx"), run(2.5, 1.0, "subspace")]) is None  # the kept start differs
    # one replay took another path, two reached one minimum: theirs
    assert chosen([run(90.59236, 48.66), run(90.59317, 48.657), run(90.59236, 48.66)]) == 0
    assert chosen([run(90.59317, 48.657), run(90.59236, 48.66), run(90.59236, 48.66)]) == 1
    assert chosen([run(2.5, 1.0), {"start": None}, {"start": None}]) is None  # failed replays agree with nothing
    numbers = {"misfit": 7076867.41, "fit": 29.36, "fit_per_output": [29.0, 29.72], "fit_overall": 1.0,
               "fit_identification": 79.31, "spectral_radius": 0.44340028, "p_ell_condition": 23456.0}
    shown, reduced = daisy_runner.printed_numbers(numbers, daisy_runner.DIGITS, False)
    assert shown == {"misfit": 7076900.0, "fit": 29.4, "fit_per_output": [29.0, 29.7], "fit_overall": 1.0,
                     "fit_identification": 79.3, "spectral_radius": 0.4434, "p_ell_condition": 23000.0} and not reduced
    shown, reduced = daisy_runner.printed_numbers(numbers, daisy_runner.DIGITS, True)
    assert shown == {"misfit": None, "fit": 30.0, "fit_per_output": [None, None], "fit_overall": None,
                     "fit_identification": None, "spectral_radius": 0.44, "p_ell_condition": None}
    assert reduced["misfit"] is None and reduced["fit"] == -1 and reduced["fit_per_output"] == [None, None]
    w = np.linspace(-3, 3, 40).reshape(20, 2)
    changed = daisy_runner.last_bit_changed(w)
    assert np.all(changed != w) and np.all(np.abs(changed - w) <= np.spacing(np.abs(w)))  # one unit in the last place
    assert 0.3 < np.mean(changed > w) < 0.7  # up and down
    assert np.array_equal(changed, daisy_runner.last_bit_changed(w))  # a fixed pattern
    assert not np.array_equal(changed, daisy_runner.last_bit_changed(w, 2))  # another for the second replay


def test_runner_rejects_bad_choices(shared):
    with pytest.raises(ValueError, match="not a data set of Table 1"):
        daisy_runner.run_benchmark(["distill2"], directory=shared, progress=None)
    with pytest.raises(ValueError, match="at least one data set"):
        daisy_runner.run_benchmark([], directory=shared, progress=None)
    with pytest.raises(ValueError, match="modes must be a non-empty selection of oe, eiv"):
        daisy_runner.run_set("erie", directory=shared, modes=["ml"])
    with pytest.raises(ValueError, match="init is an empty sequence"):
        daisy_runner.run_set("erie", directory=shared, init=[])
    with pytest.raises(ValueError, match="init: unknown start 'eiv'"):
        daisy_runner.run_set("erie", directory=shared, init="eiv")


def test_runner_with_the_papers_single_start(shared):
    # init="lra": the paper's start alone; its misfit is the first candidate's of the default run
    single = daisy_runner.run_set("robot_arm", directory=shared, download_missing=False, init="lra", modes=["eiv"])
    default = daisy_runner.run_set("robot_arm", directory=shared, download_missing=False, modes=["eiv"])
    assert [c.start for c in single.modes["eiv"].candidates] == ["lra"] and single.modes["eiv"].start == "lra"
    assert single.modes["eiv"].misfit == pytest.approx(default.modes["eiv"].candidates[0].misfit, rel=1e-12)
    # printed (and kept) to five significant digits
    assert single.modes["eiv"].misfit <= daisy_runner.REFERENCE_MISFIT["robot_arm"] * (1 + 5e-5)


# --- issue 32, hostile inputs round three (the download and the runner): bounded downloads, finished
# --- sets kept ----------------------------------------------------------------------------------------

def _gzip_bomb(single_member: bool) -> bytes:
    """A few hundred KB to a MB of gzip that expands to 256 MiB (one member) or 1 GiB (64 members of 16 MiB)."""
    if single_member:
        compressor, zeros = zlib.compressobj(9, zlib.DEFLATED, 16 + zlib.MAX_WBITS), bytes(2**20)
        return b"".join([compressor.compress(zeros) for _ in range(256)] + [compressor.flush()])
    return gzip.compress(bytes(2**24), compresslevel=9) * 64


@pytest.mark.parametrize("single_member", [True, False])
def test_a_gzip_bomb_is_refused_while_streaming(single_member, no_environment, tmp_path):
    root = tmp_path / "server"
    target = root / daisy.dataset("erie").path
    target.parent.mkdir(parents=True)
    target.write_bytes(_gzip_bomb(single_member))
    cache = tmp_path / "cache"
    with _serving(root) as url:
        tracemalloc.start()
        try:
            with pytest.raises(daisy.DownloadError, match=rf"erie.dat.gz holds more than {daisy.MAX_FILE_BYTES} "
                                                          "bytes once decompressed: not a DAISY data file"):
                daisy.data_file("erie", cache, url=url)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
    assert peak < 4 * daisy.MAX_FILE_BYTES  # never the gigabyte the payload asks for
    assert _leftovers(cache) == []


def test_an_oversized_plain_file_is_refused(no_environment, tmp_path):
    root = tmp_path / "plain"
    target = root / daisy.dataset("erie").path
    target.parent.mkdir(parents=True)
    target.write_bytes(b"1 2 3\n" * (daisy.MAX_FILE_BYTES // 6 + 1000))  # a table, but too large for DAISY
    with _serving(root) as url:
        with pytest.raises(daisy.DownloadError, match=rf"holds more than {daisy.MAX_FILE_BYTES} bytes: not a DAISY"):
            daisy.data_file("erie", tmp_path / "cache", url=url)
    assert _leftovers(tmp_path / "cache") == []


def test_gzip_members_and_truncation(shared, no_environment, tmp_path):
    content = (shared / "erie.dat").read_bytes()
    root = tmp_path / "server"
    target = root / daisy.dataset("erie").path
    target.parent.mkdir(parents=True)
    target.write_bytes(gzip.compress(content[:10_000]) + gzip.compress(content[10_000:]))  # two members
    with _serving(root) as url:
        assert daisy.data_file("erie", tmp_path / "cache", url=url).read_bytes() == content
        target.write_bytes(gzip.compress(content)[:-100])  # cut short
        with pytest.raises(daisy.DownloadError, match="not a valid gzip file"):
            daisy.data_file("erie", tmp_path / "other", url=url)
    assert _leftovers(tmp_path / "other") == []


class _Trickling(http.server.BaseHTTPRequestHandler):
    """Promises a megabyte and sends a byte every 0.2 s: no single read ever times out."""

    def do_GET(self):
        self.send_response(200)
        self.send_header("Content-Length", str(2**20))
        self.end_headers()
        for _ in range(150):  # 30 s at most, then the connection closes
            try:
                self.wfile.write(b"1")
                self.wfile.flush()
            except OSError:
                return
            time.sleep(0.2)

    def log_message(self, *args):
        pass


def test_a_trickling_server_is_given_up_after_the_download_deadline(no_environment, monkeypatch, tmp_path):
    monkeypatch.setattr(daisy, "MAX_DOWNLOAD_SECONDS", 1.0)
    with local_http_server(_Trickling) as port:  # its handlers are daemon threads: a trickle is not waited for
        started = time.monotonic()
        with pytest.raises(daisy.DownloadError, match="did not finish downloading within 1 s"):
            daisy.download("erie", tmp_path / "cache", url=f"http://127.0.0.1:{port}/", timeout=5)
        assert time.monotonic() - started < 15
    assert _leftovers(tmp_path / "cache") == []


def test_a_large_wrong_local_file_is_refused_without_reading_it_into_memory(no_environment, tmp_path):
    folder = tmp_path / "data"
    folder.mkdir()
    with open(folder / "erie.dat", "wb") as wrong:
        wrong.truncate(256 * 2**20)  # sparse: no disk used
    tracemalloc.start()
    try:
        with pytest.raises(daisy.ChecksumError, match="erie.dat has SHA-256"):
            daisy.data_file("erie", folder, download_missing=False)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 32 * 2**20
    assert (folder / "erie.dat").stat().st_size == 256 * 2**20  # the user's file is left as it was


class _InProcess:
    """An executor that runs each job here at once; `special` maps (set, mode) to an exception that submit
    raises (Dask pickles in submit), an exception the job's future holds (a worker lost), "pending", or
    "interrupt" (Ctrl-C while its result is awaited)."""

    def __init__(self, special):
        self.special, self.futures = special, {}

    def submit(self, function, name, mode, *args):
        what = self.special.get((name, mode))
        if isinstance(what, TypeError):
            raise what
        future = _Interrupting() if what == "interrupt" else concurrent.futures.Future()
        if isinstance(what, Exception):
            future.set_exception(what)
        elif what is None:
            future.set_result(function(name, mode, *args))
        self.futures[name, mode] = future
        return future


class _Interrupting(concurrent.futures.Future):
    def result(self, timeout=None):
        signal.raise_signal(signal.SIGINT)  # Python's handler raises KeyboardInterrupt here, as on Ctrl-C
        raise AssertionError("SIGINT did not interrupt")


def test_what_the_executor_cannot_do_fails_that_mode_alone(shared):
    special = {("erie", "eiv"): TypeError("Could not serialize object of type Task"),
               ("destill", "oe"): OSError("the worker died 3 times on this task")}
    results = daisy_runner.run_benchmark(["erie", "destill"], directory=shared, download_missing=False,
                                         progress=None, executor=_InProcess(special))
    erie, destill = results
    assert erie.modes["oe"].model is not None and destill.modes["eiv"].model is not None
    assert erie.modes["eiv"].model is None and erie.modes["eiv"].fit == 0
    assert erie.modes["eiv"].account == ("identification failed: the executor could not run it (TypeError: Could "
                                         "not serialize object of type Task)")
    assert "(OSError: the worker died 3 times on this task)" in destill.modes["oe"].account


def test_ctrl_c_keeps_the_finished_sets(shared, monkeypatch):
    # on an executor: erie finished in both modes (destill, submitted first, is interrupted while awaited)
    executor = _InProcess({("destill", "eiv"): "interrupt", ("destill", "oe"): "pending"})
    with pytest.raises(daisy_runner.BenchmarkInterrupted, match="interrupted with 1 of 2 sets finished") as caught:
        daisy_runner.run_benchmark(["erie", "destill"], directory=shared, download_missing=False, progress=None,
                                   executor=executor, modes=["eiv", "oe"])
    assert isinstance(caught.value, KeyboardInterrupt)
    assert [r.name for r in caught.value.results] == ["erie"]
    assert all(x.model is not None for x in caught.value.results[0].modes.values())
    assert executor.futures["destill", "oe"].cancelled()  # not left running
    # serially: the second set is interrupted
    run_set = daisy_runner.run_set

    def interrupted_destill(name, **options):
        if name == "destill":
            raise KeyboardInterrupt
        return run_set(name, **options)

    monkeypatch.setattr(daisy_runner, "run_set", interrupted_destill)
    with pytest.raises(daisy_runner.BenchmarkInterrupted, match="1 of 3 sets finished") as caught:
        daisy_runner.run_benchmark(["erie", "destill", "robot_arm"], directory=shared, download_missing=False,
                                   progress=None, modes=["oe"])
    assert [r.name for r in caught.value.results] == ["erie"] and caught.value.results[0].modes["oe"].fit > 0
