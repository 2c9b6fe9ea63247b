"""report.html in a real browser: headless Chromium through Selenium opens the pages the lab writes
(a sweep's report, a comparison, the regression history) and checks what a reader needs: no
JavaScript error, every section of report.md, every figure drawn at a non-zero size, a table that
sorts when its header is clicked, a tooltip naming a point's configuration, every table cell as
report.md has it (text such as `auto:<choice>` is text, not a tag), and nothing fetched from
outside the page. The checker is shown to fail on a page with a broken figure, on one that loads
a script from the network and on one that drops a table cell's `<choice>`. Skipped, with the reason, where no browser is installed
(scripts/bootstrap.sh installs chromium, chromium-driver and python3-selenium for make test)."""
import base64
import re
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from entry_point import run_tool
from test_regress import TH, check, frame, meta

ROOT = Path(__file__).resolve().parents[2]
BASELINE = ROOT / "results" / "baselines" / "threads"
CHROMEDRIVER = shutil.which("chromedriver")

try:
    from selenium import webdriver
    from selenium.common.exceptions import WebDriverException
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
except ImportError:
    webdriver = None

pytestmark = pytest.mark.skipif(
    webdriver is None or CHROMEDRIVER is None or shutil.which("chromium") is None,
    reason="no headless browser: install chromium, chromium-driver and python3-selenium "
           "(scripts/bootstrap.sh does for make test)")


@pytest.fixture(scope="module")
def browser():
    options = webdriver.ChromeOptions()
    for argument in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                     "--window-size=1300,1000"):
        options.add_argument(argument)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    try:
        driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
    except WebDriverException as err:
        pytest.skip(f"chromium did not start: {err.msg}")
    yield driver
    driver.quit()


def leading_number(text: str):
    match = re.match(r"[+-]?(\d+\.?\d*|\.\d+)(e[+-]?\d+)?", text.replace(",", ""), re.I)
    return float(match.group(0)) if match else None


def sort_problem(driver) -> str | None:
    """Clicks the header of the first numeric column, in any table, whose rows are not already
    in order; the column must then read ascending, and after a second click descending."""
    for table in driver.find_elements(By.CSS_SELECTOR, "table"):
        headers = table.find_elements(By.CSS_SELECTOR, "thead th")
        for column, header in enumerate(headers):
            def values():
                cells = table.find_elements(By.CSS_SELECTOR,
                                            f"tbody tr td:nth-child({column + 1})")
                return [leading_number(c.text) for c in cells]
            before = values()
            if len(before) < 3 or None in before or before == sorted(before):
                continue
            driver.execute_script("arguments[0].scrollIntoView({block: 'center'})", header)
            header.click()
            if values() != sorted(before):
                return f"column {header.text!r} did not sort ascending: {values()}"
            header.click()
            if values() != sorted(before, reverse=True):
                return f"column {header.text!r} did not sort descending: {values()}"
            return None
    return "no table with an unsorted numeric column to sort"


def hover_problem(driver) -> str | None:
    """Moves the pointer onto a point of every figure (one not covered by a neighbour's target):
    the tooltip must show that point's configuration ("name=value") and its value."""
    topmost = ("const r = arguments[0].getBoundingClientRect();"
               "return document.elementFromPoint(r.x + r.width / 2, r.y + r.height / 2)"
               " === arguments[0];")
    for figure in driver.find_elements(By.CSS_SELECTOR, ".plot"):
        points = figure.find_elements(By.CSS_SELECTOR, ".pt")
        if not points:
            continue
        driver.execute_script("arguments[0].scrollIntoView({block: 'center'})", figure)
        point = next((p for p in points if driver.execute_script(topmost, p)), None)
        if point is None:
            return "every point of a figure is covered by another"
        ActionChains(driver).move_to_element(point).move_by_offset(1, 0).perform()
        tip = driver.find_element(By.ID, "tip")
        expected = point.get_attribute("data-tip")
        if not tip.is_displayed() or tip.text.split() != expected.split() or "=" not in expected:
            return f"hovering a point showed {tip.text!r}, expected {expected!r}"
    return None


def markdown_cells(markdown: str) -> list[str]:
    """Every header and body cell of the Markdown's tables as a reader sees it: code marks,
    bold marks, link targets and the escapes of '|' taken off."""
    cells = []
    for line in markdown.splitlines():
        if not line.startswith("|") or re.fullmatch(r"\|[-:|]+\|", line):
            continue
        for cell in re.split(r"(?<!\\)\|", line.strip())[1:-1]:
            cell = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", cell)  # a link reads as its text
            cells.append(cell.strip().replace("\\|", "|").replace("`", "").replace("**", ""))
    return cells


def cell_problem(driver, markdown: str) -> str | None:
    """The first table cell whose visible text differs from report.md's."""
    shown = [c.text.strip() for c in driver.find_elements(By.CSS_SELECTOR, "th, td")]
    expected = markdown_cells(markdown)
    for index, (seen, written) in enumerate(zip(shown, expected)):
        if seen != written:
            return f"table cell {index} reads {seen!r}, report.md has {written!r}"
    if len(shown) != len(expected):
        return f"{len(shown)} table cells shown, report.md has {len(expected)}"
    return None


def page_problems(driver, page: Path, interactive: bool = True) -> list[str]:
    problems = []
    text = page.read_text()
    if re.search(r"(https?:)?//[a-z0-9.-]+\.[a-z]{2,}", text, re.I):
        problems.append("the page holds an external URL")
    driver.get(page.resolve().as_uri())
    for entry in driver.get_log("browser"):
        if entry["level"] == "SEVERE":
            problems.append(f"browser error: {entry['message']}")
    if driver.execute_script("return performance.getEntriesByType('resource').length"):
        problems.append("the page fetched a resource")
    markdown = page.with_suffix(".md").read_text()
    sections = re.findall(r"^## (.+)$", markdown, re.MULTILINE)
    shown = [h.text for h in driver.find_elements(By.TAG_NAME, "h2")]
    if shown != sections:
        problems.append(f"sections {shown} differ from report.md's {sections}")
    images = driver.find_elements(By.TAG_NAME, "img")
    figures = len(re.findall(r"!\[", markdown))
    if len(images) != figures:
        problems.append(f"{len(images)} figures shown, report.md has {figures}")
    for image in images:
        width, height = driver.execute_script(
            "const r = arguments[0].getBoundingClientRect();"
            "return [arguments[0].complete ? arguments[0].naturalWidth : 0, r.height];", image)
        if not (width > 0 and height > 0):
            problems.append(f"figure {image.get_attribute('alt')!r} did not render")
    if driver.find_elements(By.CSS_SELECTOR, ".missing"):
        problems.append("a figure is missing")
    if (cells := cell_problem(driver, markdown)) is not None:
        problems.append(cells)
    if interactive:
        problems += [p for p in (sort_problem(driver), hover_problem(driver)) if p]
    return problems


@pytest.fixture(scope="module")
def sweep_page(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sweep") / "threads"
    folder.mkdir()
    for name in ("runs.csv", "meta.json"):
        shutil.copy(BASELINE / name, folder / name)
    assert run_tool("plots", folder, "--no-svg").returncode == 0
    return folder / "report.html"


def test_the_sweep_report_works_in_a_browser(browser, sweep_page):
    assert page_problems(browser, sweep_page) == []
    # Every figure of report.md is inside the page, and the page needs no other file.
    assert sweep_page.read_text().count("data:image/png;base64,") >= 5


def test_the_comparison_works_in_a_browser(browser, sweep_page, tmp_path):
    out = tmp_path / "compare"
    made = run_tool("compare", sweep_page.parent, sweep_page.parent, "--out", out, "--no-svg")
    assert made.returncode == 0, made.stderr
    assert page_problems(browser, out / "compare.html") == []


def test_the_regression_history_works_in_a_browser(browser, tmp_path):
    from analysis.regress.report import draw_history, history_rows, write_report
    rng = np.random.default_rng(3)
    baseline = frame(rng)
    _, reasons, comparisons, hashes = check(baseline, frame(rng, scale={"crowd cells T=1": 1.3}))
    days = []
    for day in range(1, 9):
        run = meta()
        run["date"] = f"2026-11-{day:02d}T03:00:00Z"
        run["git"] = {"commit": f"{day:040x}", "commit_date": f"2026-11-{day:02d}T01:00:00Z"}
        days.append(history_rows(check(baseline, frame(rng))[2], run, meta()))
    history = pd.concat(days, ignore_index=True)
    plots = draw_history(history, "AMD EPYC", TH, tmp_path / "plots")
    write_report(tmp_path / "report.md", meta(), meta(), {"instructions": [], "wall": []},
                 comparisons, hashes, [], reasons, plots, TH)
    page = tmp_path / "report.html"
    assert page_problems(browser, page) == []
    verdicts = page.read_text().split("<h2>")[1]  # the first section: the last run's verdicts
    assert verdicts.startswith("Verdicts") and "REGRESSED" in verdicts.split("</tr>")[1]


def test_the_checker_fails_on_a_broken_figure_and_an_external_script(browser, sweep_page,
                                                                     tmp_path):
    text = sweep_page.read_text()
    broken = tmp_path / "broken.html"
    shutil.copy(sweep_page.with_suffix(".md"), broken.with_suffix(".md"))
    first = text.index("data:image/png;base64,") + len("data:image/png;base64,")
    broken.write_text(text[:first] + base64.b64encode(b"not a png").decode() + text[first + 40:])
    assert any("did not render" in p for p in page_problems(browser, broken, interactive=False))

    fetching = tmp_path / "fetching.html"
    shutil.copy(sweep_page.with_suffix(".md"), fetching.with_suffix(".md"))
    fetching.write_text(text.replace("</body>",
                                     '<script src="https://cdn.example.org/x.js"></script></body>'))
    assert "the page holds an external URL" in page_problems(browser, fetching, interactive=False)


def test_the_scoreboard_of_a_grading_links_each_report(browser, tmp_path):
    import json
    from build_path import BUILD
    folder = tmp_path / "submissions"
    folder.mkdir()
    for name, built in (("alice", "plain_allpairs"), ("bob", "check_programs/wall_tolerance")):
        shutil.copy(BUILD / built, folder / name)
    config = json.loads((ROOT / "configs" / "grade.json").read_text())
    config["judging"].update(scenes=config["judging"]["scenes"][:2], T=[1])
    config["timing"].update(scene={"N": 40, "L": 2000, "r": 1, "S": 20}, repetitions=1,
                            warmup=0)
    (tmp_path / "grade.json").write_text(json.dumps(config))
    out = tmp_path / "out"
    done = run_tool("grade", folder, "--out", out, "--config", tmp_path / "grade.json",
                    "--psweep", BUILD / "psweep", timeout=300)
    assert done.returncode == 0, done.stderr
    board = out / "scoreboard.html"
    assert page_problems(browser, board, interactive=False) == []
    assert browser.title.startswith("Scoreboard: 2 submissions of ")
    assert [a.text for a in browser.find_elements(By.TAG_NAME, "a")] == ["report", "report"]
    browser.find_element(By.CSS_SELECTOR, 'a[href="reports/bob.html"]').click()
    assert browser.current_url.endswith("/reports/bob.html")
    assert browser.find_element(By.TAG_NAME, "h3").text == "drawn/corner.in, T = 1"
    assert page_problems(browser, out / "reports" / "bob.html", interactive=False) == []
    # The class report: its figures drawn, its examples linked to the reports.
    assert page_problems(browser, out / "class.html", interactive=False) == []
    assert browser.title.startswith("The class: 2 submissions of ")
    assert len(browser.find_elements(By.CSS_SELECTOR, "span.plot img")) == 2
    assert hover_problem(browser) is None


QUOTED = ("| engine | about |\n|---|---|\n| auto | picks; reports auto:<choice> |\n"
          "| prog | wrote <a@b.c> and `x<y>` |\n")


def test_text_that_looks_like_html_reads_as_in_the_markdown(browser, tmp_path):
    from analysis.common.page import write_pages
    page = write_pages(tmp_path / "report.md",
                       "# Quoted\n\n## Text\n\npsim reports auto:<choice>; <div>x</div> and "
                       "1 < 2\n\n" + QUOTED)
    assert page_problems(browser, page, interactive=False) == []
    body = browser.find_element(By.TAG_NAME, "body").text
    for phrase in ("psim reports auto:<choice>; <div>x</div> and 1 < 2",
                   "reports auto:<choice>", "wrote <a@b.c> and x<y>"):
        assert phrase in body
    # The checker sees a page that lost the word: <choice> read as an unknown tag.
    lost = tmp_path / "lost.html"
    shutil.copy(page.with_suffix(".md"), lost.with_suffix(".md"))
    lost.write_text(page.read_text().replace("auto:&lt;choice&gt;</td>", "auto:<choice></td>"))
    assert any("reads 'picks; reports auto:'" in p
               for p in page_problems(browser, lost, interactive=False))
