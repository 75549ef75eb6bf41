"""`homebot inspect`'s page in a real browser (Debian's chromium through chromium-driver and selenium)."""

from __future__ import annotations

import importlib.util
import json
import shutil
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from inspector_runs import bus, clean_blackboard, live_run, record_run  # noqa: F401 - fixtures
from worlds.bus.keys import Keys
from worlds.bus.session import free_tcp_endpoint, open_session
from agent.app.inspector.history import History
from agent.app.inspector.server import Inspector
from agent.app.inspector.sources import LiveAgent, load_run

webdriver = pytest.importorskip("selenium.webdriver")
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.support.ui import WebDriverWait  # noqa: E402

pytestmark = [pytest.mark.slow, pytest.mark.skipif(
    not (shutil.which("chromium") and shutil.which("chromedriver")),
    reason="needs chromium and chromium-driver: apt-get install -y chromium chromium-driver")]
NO_CONTROL = importlib.util.find_spec("agent.app.runtime.control") is None



@pytest.fixture
def browser() -> Iterator[Any]:
    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium")
    for argument in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu"):
        options.add_argument(argument)
    driver = webdriver.Chrome(service=webdriver.ChromeService(executable_path=shutil.which("chromedriver")),
                              options=options)
    try:
        yield driver
    finally:
        driver.quit()


def statuses(driver: Any) -> dict[str, str]:
    """Each drawn behaviour's name and the status its colour shows."""
    return {node.get_attribute("data-name"): node.get_attribute("data-status")
            for node in driver.find_elements(By.CSS_SELECTOR, "g.node")}


def tick(driver: Any) -> int:
    text = driver.find_element(By.ID, "tick").text
    return int(text) if text.isdigit() else -1


def test_a_recorded_run_shows_the_tree_and_the_timeline_replays_it(tmp_path: Path, browser: Any) -> None:
    record_run(tmp_path / "run", ticks=6)
    history = History()
    load_run(tmp_path / "run", history)
    server = Inspector(history, {"mode": "recorded", "source": "run"})
    try:
        browser.get(server.start())
        wait = WebDriverWait(browser, 20)
        wait.until(lambda d: tick(d) == 6)
        assert statuses(browser) == {"Episode": "FAILURE", "Count": "SUCCESS", "Check": "FAILURE"}
        fill = browser.find_element(By.CSS_SELECTOR, 'g.node[data-name="Check"] rect').value_of_css_property("fill")
        assert fill == "rgb(246, 196, 196)"  # failure red
        slider = browser.find_element(By.ID, "timeline")
        browser.execute_script("arguments[0].value = 0; arguments[0].dispatchEvent(new Event('input'))", slider)
        wait.until(lambda d: tick(d) == 1)
        assert statuses(browser) == {"Episode": "RUNNING", "Count": "RUNNING", "Check": "INVALID"}
        assert browser.find_element(By.CSS_SELECTOR, 'g.node[data-name="Count"]').get_attribute("data-visited") == "true"
        assert "5 to go" in browser.find_element(By.ID, "messages").text
        assert "/count" in browser.find_element(By.ID, "blackboard").text
        assert "1 Count init /count" in browser.find_element(By.ID, "activity").text
        browser.execute_script("arguments[0].value = 3; arguments[0].dispatchEvent(new Event('input'))", slider)
        wait.until(lambda d: tick(d) == 4)
        assert "2 to go" in browser.find_element(By.ID, "messages").text
    finally:
        server.close()



def test_a_live_run_shows_the_tree_and_the_tick_count_advancing(bus: tuple[Any, Any], browser: Any) -> None:
    agent_session, session = bus
    keys = Keys("homebot/live-page")
    history = History()
    live = LiveAgent(session, keys.namespace, history)
    server = Inspector(history, {"mode": "live", "source": "test"}, controller=live.control)
    try:
        browser.get(server.start())
        thread = live_run(agent_session, keys.agent_tree, ticks=150, period_s=0.03)
        wait = WebDriverWait(browser, 30)
        wait.until(lambda d: tick(d) > 0)
        assert statuses(browser)["Count"] == "RUNNING"
        seen = tick(browser)
        wait.until(lambda d: tick(d) > seen + 5)
        thread.join(30)
    finally:
        server.close()
        live.close()


# --- control (the agent's side: agent.app.runtime.control) ------------------------------------


@pytest.fixture
def live_episode(tmp_path: Path) -> Iterator[dict[str, Any]]:
    """A real episode, run in a thread with a namespace and a listen endpoint, and an inspector on it."""
    from agent.app.config import load_config
    from agent.app.runtime.run import RunRequest, run_episode

    endpoint, namespace = free_tcp_endpoint(), "homebot/inspect-control"
    # paced, so the episode outlasts the page loading: a viewer that joins late sees the tree at the
    # next full snapshot (every few seconds), and a fast episode may be over by then
    config = load_config(overrides=[f'bus.listen=["{endpoint}"]', "episode.budget=30", "stop.rule=budget",
                                    "episode.tick_period_s=0.05"])
    outcome: dict[str, Any] = {}
    runner = threading.Thread(target=lambda: outcome.update(run_episode(RunRequest(
        seed=3, config=config, out_root=tmp_path, namespace=namespace, run_id="inspected"))), daemon=True)
    runner.start()
    session = open_session(connect=[endpoint])
    history = History()
    live = LiveAgent(session, namespace, history)
    server = Inspector(history, {"mode": "live", "source": namespace}, controller=live.control,
                       result=lambda: live.outcome)
    try:
        yield {"url": server.start(), "live": live, "runner": runner, "outcome": outcome, "folder": tmp_path / "inspected"}
    finally:
        live.control("continue", b"{}")
        server.close()
        live.close()
        session.close()
        runner.join(120)


def click_node(driver: Any, name: str) -> None:
    driver.execute_script("arguments[0].dispatchEvent(new MouseEvent('click', {bubbles: true}))",
                          driver.find_element(By.CSS_SELECTOR, f'g.node[data-name="{name}"]'))


def open_on(driver: Any, episode: dict[str, Any], name: str) -> WebDriverWait:
    """Open the page of ``episode``, wait for the tree and select the behaviour ``name``; a long wait."""
    driver.get(episode["url"])
    wait = WebDriverWait(driver, 60)
    wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, f'g.node[data-name="{name}"]'))
    click_node(driver, name)
    return wait


def control_text(driver: Any) -> str:
    return driver.find_element(By.ID, "control-state").text


@pytest.mark.skipif(NO_CONTROL, reason="the agent's control side (agent.app.runtime.control) is not here")
def test_a_breakpoint_stops_the_ticks_and_step_runs_exactly_one(live_episode: dict[str, Any], browser: Any) -> None:
    wait = open_on(browser, live_episode, "Navigate")
    browser.find_element(By.ID, "breakpoint").click()
    wait.until(lambda d: "paused before Navigate" in control_text(d))
    stopped = live_episode["live"].control("state", b"{}")["tick"]
    time.sleep(0.5)  # a paused agent completes no tick, however long one waits
    assert live_episode["live"].control("state", b"{}")["tick"] == stopped
    assert "breakpoints: Navigate" in control_text(browser)
    browser.find_element(By.ID, "breakpoint").click()  # off again
    wait.until(lambda d: "breakpoints" not in control_text(d))
    browser.find_element(By.ID, "step").click()
    wait.until(lambda d: "paused" in control_text(d) and f"tick {stopped + 1}" in control_text(d))
    browser.find_element(By.ID, "step").click()
    wait.until(lambda d: f"tick {stopped + 2};" in control_text(d) + ";")
    assert live_episode["live"].control("state", b"{}")["tick"] == stopped + 2
    browser.find_element(By.ID, "continue").click()
    wait.until(lambda d: control_text(d).startswith("running"))


@pytest.mark.skipif(NO_CONTROL, reason="the agent's control side (agent.app.runtime.control) is not here")
def test_an_injected_failure_shows_in_the_page_and_in_the_result(live_episode: dict[str, Any], browser: Any) -> None:
    wait = open_on(browser, live_episode, "Navigate")
    browser.find_element(By.ID, "inject-failure").click()
    # the control bar says so, or, once the failure has ended the episode, its outcome does
    wait.until(lambda d: "failure in Navigate" in control_text(d) + d.find_element(By.ID, "outcome").text)
    wait.until(lambda d: d.find_element(By.CSS_SELECTOR, 'g.node[data-name="Navigate"]').get_attribute(
        "data-status") == "FAILURE" or not live_episode["runner"].is_alive())
    live_episode["runner"].join(120)
    result = json.loads((live_episode["folder"] / "result.json").read_text())
    assert [(i["behaviour"], i["fault"]) for i in result["injected"]] == [("Navigate", "failure")]
