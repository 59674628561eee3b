"""What a notebook shows: every result an HTML fragment (never a page), its style scoped to
its own div, the numbers it holds."""
import re
import warnings

import pytest

import physid
from conftest import KUKA_URDF, ROOT, kuka_run


def fragment_checks(html, scope):
    assert "<!DOCTYPE" not in html and "<html" not in html and "<body" not in html
    assert html.startswith(f'<div class="{scope}">') and html.rstrip().endswith("</div>")
    styles = re.findall(r"<style>(.*?)</style>", html, flags=re.S)
    assert len(styles) == 1
    selectors = [s.strip() for rule in re.findall(r"([^{}]+)\{", styles[0]) for s in rule.split(",")]
    assert selectors and all(s.startswith(f".{scope}") for s in selectors), selectors


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", physid.PhysidWarning)
        kuka = physid.Robot(KUKA_URDF)
        fit = physid.identify(kuka, kuka_run(1), validate_data=kuka_run(2), constraints="consistent")
        return kuka, fit, physid.diagnose(kuka, kuka_run(3))


def test_every_result_is_a_scoped_fragment(results, tmp_path):
    kuka, fit, d = results
    fragment_checks(d._repr_html_(), "physid-report")
    assert d._repr_html_().count("<svg") >= 2 and d.summary.split(";")[0] in d._repr_html_()
    others = [kuka, fit,
              physid.compare(f"{ROOT}/results/ci_baseline", variant="ellipsoid<=consistent", allow_too_few=True),
              physid.excite("cheetah3", iterations=20, starts=1, duration=3.0),
              physid.experiment(f"{ROOT}/scenarios/ci.toml", seeds=1, threads=1),
              physid.simulate(f"{ROOT}/scenarios/cheetah3_shell.toml", tmp_path / "run.mcap", duration=0.5)]
    for result in others:
        fragment_checks(result._repr_html_(), "physid-result")


def test_the_views_hold_the_results_numbers(results):
    _, fit, d = results
    html = fit._repr_html_()
    assert f"{fit.validation_rms:.4f} N m" in html and "consistent" in html
    assert html.count("<tr>") == 1 + len(fit.bodies())
    # The page (report.html, write_report) wraps the same fragment.
    assert d._repr_html_() in d.html() and d.html().startswith("<!DOCTYPE html>")
