"""The renderer's live page in a launched graph: source -> stand-in responder -> renderer (serve).

The responder follows the Control messages the page puts on the bus, so a control posted to the
page must come back as a differently coloured partner in the rendered video.
"""

from __future__ import annotations

import http.client
import json
import shutil
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from typing import Any

import cv2
import numpy as np
import pytest

from counterpart.body.camera import default_camera
from counterpart.nodes.renderer import draw
from tests.launching import descendants, read_jsonl, start_launch, stop_launch, wait_for, write_launch
from tests.renderer_nodes import partner_joints

W, H = 160, 120


@pytest.fixture(scope="module")
def live(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    tmp = tmp_path_factory.mktemp("web")
    port_file = tmp / "port"
    file = write_launch(
        tmp / "graph.yaml",
        {
            "nodes": {
                "source": {
                    "run": "tests.renderer_nodes:SceneSource",
                    "params": {"count": 100000, "rate": 20.0, "width": W, "height": H, "partner": False},
                },
                "calibration": {"run": "counterpart.nodes.calibration"},
                "responder": {
                    "run": "tests.renderer_nodes:ControlledResponder",
                    "params": {"path": str(tmp / "controls.jsonl")},
                    "restart": "on-failure",
                },
                "renderer": {
                    "run": "counterpart.nodes.renderer",
                    "params": {
                        "serve": True,
                        "port": 0,
                        "port_file": str(port_file),
                        "stats_topics": ["source/stats", "responder/stats"],
                        "models": ["dual-hmm", "listener"],
                    },
                },
            }
        },
    )
    proc = start_launch(file)
    try:
        assert wait_for(lambda: port_file.exists() and port_file.read_text().strip(), timeout=30), "no port file"
        port = int(port_file.read_text())
        url = f"http://127.0.0.1:{port}"
        assert wait_for(lambda: _get(url + "/frame.jpg")[0] == 200, timeout=30), "no frame rendered"
        yield {"url": url, "port": port, "controls": tmp / "controls.jsonl", "proc": proc}
    finally:
        stop_launch(proc)


def _get(url: str, headers: dict[str, str] | None = None) -> tuple[int, bytes, Any]:
    req = urllib.request.Request(url, headers=headers or {})
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            return r.status, r.read(), r.headers
    except urllib.error.HTTPError as e:
        return e.code, e.read(), e.headers
    except (urllib.error.URLError, ConnectionError):
        return 0, b"", {}


def _post(url: str, body: Any, ctype: str = "application/json") -> tuple[int, Any]:
    data = body if isinstance(body, bytes) else json.dumps(body).encode()
    req = urllib.request.Request(url, data=data, headers={"Content-Type": ctype}, method="POST")
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read())


def _frame(url: str) -> np.ndarray:
    status, data, _ = _get(url + "/frame.jpg")
    assert status == 200
    return cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)


def read_parts(port: int, n: int) -> list[tuple[int, bytes]]:
    """The first ``n`` parts of /stream.mjpg as (X-Frame-Seq, JPEG bytes)."""
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    conn.request("GET", "/stream.mjpg")
    r = conn.getresponse()
    assert r.status == 200
    ctype = r.getheader("Content-Type")
    assert ctype.startswith("multipart/x-mixed-replace; boundary=")
    boundary = b"--" + ctype.split("boundary=")[1].encode()
    parts = []
    while len(parts) < n:
        line = r.fp.readline().strip()
        if line != boundary:
            continue
        headers = {}
        while h := r.fp.readline().strip():
            k, _, v = h.decode().partition(":")
            headers[k.strip().lower()] = v.strip()
        parts.append((int(headers["x-frame-seq"]), r.fp.read(int(headers["content-length"]))))
    conn.close()
    return parts


def partner_core() -> np.ndarray:
    """(H, W) bool: pixels inside the partner in every frame (its arm moves; its body does not)."""
    cam = default_camera(W, H)  # the renderer's camera by default: the tracker's at the frame size
    core = np.ones((H, W), bool)
    for seq in range(0, 40, 3):
        m = (draw.draw_partner_3d(np.zeros((H, W, 3), np.uint8), partner_joints(seq), cam) > 0).any(-1)
        core &= cv2.erode(m.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
    core[-30:] = False  # the control strip
    core[:45] = False  # the stats box (three nodes' lines) darkens the top rows once stats arrive
    assert core.sum() > 100
    return core


def mean_bgr(img: np.ndarray, mask: np.ndarray) -> np.ndarray:
    return img[mask].astype(float).mean(0)


def test_page_and_stream_frames_advance(live: dict[str, Any]) -> None:
    status, page, headers = _get(live["url"] + "/")
    assert status == 200 and headers["Content-Type"].startswith("text/html")
    text = page.decode()
    for needle in ('src="/stream.mjpg"', 'id="strength"', 'id="emotion"', 'id="interest"', 'id="model"', "/control"):
        assert needle in text
    parts = read_parts(live["port"], 3)
    seqs = [s for s, _ in parts]
    assert seqs == sorted(seqs) and len(set(seqs)) == 3
    imgs = [cv2.imdecode(np.frombuffer(d, np.uint8), cv2.IMREAD_COLOR) for _, d in parts]
    assert all(i.shape == (H, W, 3) for i in imgs)
    assert np.abs(imgs[0].astype(int) - imgs[-1]).max() > 100  # the scene's bar moved


def test_posted_control_reaches_the_bus_and_changes_the_partner(live: dict[str, Any]) -> None:
    core = partner_core()
    status, body = _post(live["url"] + "/control", {"emotion": "happy", "strength": 0.9, "interest": 3})
    assert status == 200 and body == {"emotion": "happy", "strength": 0.9, "interest": 3}
    assert wait_for(
        lambda: any(
            c["strength"] == 0.9 and c["emotion"] == "happy" and c["interest"] == 3
            for c in read_jsonl(live["controls"])
        ),
        timeout=10,
    ), "no Control on the bus"
    # the responder turned the partner happy (orange: red high, blue low) and the page shows it
    assert wait_for(lambda: (lambda b: b[2] - b[0] > 80)(mean_bgr(_frame(live["url"]), core)), timeout=10)
    state = json.loads(_get(live["url"] + "/state")[1])
    assert state["controls"]["strength"] == 0.9 and state["models"] == ["dual-hmm", "listener"]
    _post(live["url"] + "/control", {"strength": 0.0})
    assert wait_for(lambda: (lambda b: b[0] - b[2] > 30)(mean_bgr(_frame(live["url"]), core)), timeout=10)


def test_a_restarted_responder_gets_the_controls_in_force(live: dict[str, Any]) -> None:
    # the page's control topic is latched: a responder that comes back after a crash is sent the
    # controls in force (all of them, not only the last one posted), without anything posted again
    assert _post(live["url"] + "/control", {"emotion": "sad", "interest": 2})[0] == 200
    assert _post(live["url"] + "/control", {"strength": 0.4})[0] == 200
    want = {"emotion": "sad", "interest": 2, "strength": 0.4}
    in_force = lambda c: all(c[k] == v for k, v in want.items())  # noqa: E731
    assert wait_for(lambda: any(map(in_force, read_jsonl(live["controls"]))), timeout=10)
    (responder,) = [p for p in descendants(live["proc"].pid) if p.cmdline()[-1].endswith("/responder.json")]
    n = len(read_jsonl(live["controls"]))
    responder.kill()
    assert wait_for(lambda: any(map(in_force, read_jsonl(live["controls"])[n:])), timeout=20), (
        "the restarted responder did not get the controls in force"
    )


def test_bad_requests_are_answered_clearly(live: dict[str, Any]) -> None:
    status, body = _post(live["url"] + "/control", {"strength": 3})
    assert status == 400 and "strength" in body["error"]
    status, body = _post(live["url"] + "/control", b"not json")
    assert status == 400
    status, body = _post(live["url"] + "/control", {"strength": 0.5}, ctype="text/plain")
    assert status == 415
    assert _get(live["url"] + "/nothing")[0] == 404
    # bound to loopback: a foreign Host header (DNS rebinding) is refused
    assert _get(live["url"] + "/state", headers={"Host": "evil.example:80"})[0] == 403
    assert _get(live["url"] + "/state", headers={"Host": f"localhost:{live['port']}"})[0] == 200


def test_stats_and_snapshot(live: dict[str, Any]) -> None:
    def stats() -> dict[str, Any]:
        return json.loads(_get(live["url"] + "/stats")[1])

    assert wait_for(lambda: {"source", "responder"} <= set(stats()), timeout=30)
    # the source's measured rate is there; a loaded machine may publish below the 20 Hz asked for,
    # never above it (the rate itself is a bench figure, not a test's)
    assert wait_for(lambda: stats()["source"]["rate_hz"] > 0, timeout=30)
    s = stats()
    assert 0 < s["source"]["rate_hz"] <= 20.0 * 1.5
    assert s["responder"]["inputs"][0]["topic"] == "frame"
    status, data, headers = _get(live["url"] + "/snapshot.png")
    assert status == 200 and headers["Content-Type"] == "image/png"
    assert cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR).shape == (H, W, 3)


# ------------------------------------------------------------------------------- headless browser
def _browser() -> tuple[str, str] | str:
    """(chromium, chromedriver) paths, or the reason there is no browser to test with."""
    try:
        import selenium  # noqa: F401
    except ImportError:
        return "selenium is not installed (pip install selenium)"
    chrome = next((p for p in map(shutil.which, ("chromium", "chromium-browser", "google-chrome")) if p), None)
    driver = shutil.which("chromedriver")
    if not chrome or not driver:
        return "no Chromium and chromedriver on PATH (apt-get install chromium chromium-driver)"
    return chrome, driver


BROWSER = _browser()


@pytest.mark.skipif(isinstance(BROWSER, str), reason=f"headless browser test: {BROWSER}")
def test_in_a_headless_browser(live: dict[str, Any]) -> None:
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    from selenium.webdriver.support.ui import Select, WebDriverWait

    chrome, chromedriver = BROWSER
    opts = Options()
    opts.binary_location = chrome
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu", "--window-size=1200,900"):
        opts.add_argument(arg)
    driver = webdriver.Chrome(service=Service(chromedriver), options=opts)
    try:
        driver.get(live["url"] + "/")
        WebDriverWait(driver, 20).until(
            lambda d: d.find_element(By.TAG_NAME, "body").get_attribute("data-ready") == "1"
        )
        video = driver.find_element(By.ID, "video")
        WebDriverWait(driver, 20).until(lambda d: d.execute_script("return arguments[0].naturalWidth", video) == W)
        # frames advance in the page: two screenshots of the video element differ
        shots = []
        for _ in range(2):
            shots.append(cv2.imdecode(np.frombuffer(video.screenshot_as_png, np.uint8), cv2.IMREAD_COLOR))
            time.sleep(0.6)
        assert shots[0].shape == shots[1].shape and np.abs(shots[0].astype(int) - shots[1]).max() > 100
        # the stats panel fills from /stats
        WebDriverWait(driver, 10).until(lambda d: "source" in d.find_element(By.ID, "stats").text)
        # choose an emotion, then move the strength slider to its end with the keyboard
        Select(driver.find_element(By.ID, "emotion")).select_by_value("angry")
        slider = driver.find_element(By.ID, "strength")
        slider.click()
        slider.send_keys(Keys.END)
        assert slider.get_attribute("value") == "1"
        WebDriverWait(driver, 10).until(lambda d: int(d.find_element(By.ID, "sent-count").text) >= 2)
        assert wait_for(
            lambda: (
                any(c["strength"] == 1.0 for c in read_jsonl(live["controls"]))
                and any(c["emotion"] == "angry" for c in read_jsonl(live["controls"]))
            ),
            timeout=10,
        )
        core = partner_core()
        assert wait_for(
            lambda: (lambda b: b[2] - b[0] > 100 and b[2] - b[1] > 100)(mean_bgr(_frame(live["url"]), core)), timeout=10
        ), "the partner did not turn angry red"

        def red_in_page() -> int:
            shot = cv2.imdecode(np.frombuffer(video.screenshot_as_png, np.uint8), cv2.IMREAD_COLOR).astype(int)
            return int(((shot[..., 2] > 150) & (shot[..., 0] < 90) & (shot[..., 1] < 90)).sum())

        assert wait_for(lambda: red_in_page() > 300, timeout=10), "the page's video does not show the red partner"
    finally:
        driver.quit()


def test_a_port_in_use_is_said_and_ends_the_renderer_with_2() -> None:
    """Another program holds the page's port: the renderer says which port and how to choose
    another, and ends with 2 (a bad parameter) instead of a traceback.
    """
    with socket.socket() as held:
        held.bind(("127.0.0.1", 0))
        held.listen(1)
        port = held.getsockname()[1]
        r = subprocess.run(
            [sys.executable, "-m", "counterpart.bus.cli", "run", "counterpart.nodes.renderer"]
            + ["--param", "serve=true", "--param", f"port={port}"],
            capture_output=True,
            text=True,
            timeout=60,
        )
    assert r.returncode == 2, r.stderr[-2000:]
    assert f"parameter 'port': cannot serve the web page on 127.0.0.1:{port}" in r.stderr
    assert "choose another port" in r.stderr and "Traceback" not in r.stderr
