"""The README and docs/: the user's page stays short, links resolve, examples are true."""

from pathlib import Path
import re

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
README = REPO / 'README.md'
DOCS = [README, *sorted((REPO / 'docs').glob('*.md'))]
LINK = re.compile(r'\[[^\]]*\]\(([^)\s]+)\)')


def slug(heading: str) -> str:
    """Return GitHub's anchor for a Markdown heading."""
    return re.sub(r'[^\w\- ]', '', heading.strip().lower()).replace(' ', '-')


def anchors(path: Path) -> set[str]:
    text = re.sub(r'```.*?```', '', path.read_text(), flags=re.DOTALL)
    return {slug(line.lstrip('#')) for line in text.splitlines() if line.startswith('#')}


def test_readme_is_the_users_page():
    text = README.read_text()
    assert len(text.splitlines()) < 250
    assert 'make run ' in text and 'make test ' in text  # the two commands, as written
    assert '.venv/bin/traj-gen' in text and '.venv/bin/generator' in text
    assert 'python -m traj_gen_ros' not in text and 'PYTHONPATH' not in text
    for page in ('docs/node.md', 'docs/cli.md', 'docs/core.md', 'docs/maintainers.md'):
        assert f']({page})' in text, page


def test_the_split_docs_exist_with_their_sections():
    sections = {
        'node.md': ['Running it', 'Parameters', 'Topics and services', 'Request rules',
                    'Request limits'],
        'cli.md': ['Argument grammar', 'Exit codes and errors', '`traj-gen solve`',
                   '`traj-gen plot`', '`traj-gen fk`', '`traj-gen ik`',
                   '`traj-gen goal` and `traj-gen via`', '`traj-gen pose`'],
        'core.md': ['API', 'Profiles and their equations', 'Cubic', 'Quintic', 'Minimum time'],
        'maintainers.md': ['Architecture', 'Reliability design', 'Tests', 'Figures',
                           'Bug history', 'Known limits'],
    }
    for name, headings in sections.items():
        found = anchors(REPO / 'docs' / name)
        for heading in headings:
            assert slug(heading) in found, (name, heading)


@pytest.mark.parametrize('path', DOCS, ids=lambda path: path.name)
def test_relative_links_and_anchors_resolve(path):
    for target in LINK.findall(path.read_text()):
        if target.startswith(('http://', 'https://')):
            continue
        file_part, _, anchor = target.partition('#')
        linked = (path.parent / file_part).resolve() if file_part else path
        assert linked.exists(), (path.name, target)
        if anchor:
            assert anchor in anchors(linked), (path.name, target)


def test_readme_python_example_runs_and_its_comments_hold():
    text = README.read_text()
    code = re.search(r'```python\n(.*?)```', text, flags=re.DOTALL)[1]
    namespace: dict = {}
    exec(compile(code, 'README.md', 'exec'), namespace)  # noqa: S102 - our own example
    cubic, path, plan = namespace['cubic'], namespace['path'], namespace['plan']
    assert np.degrees(cubic.coefficients[0, :, 0]) == pytest.approx([15, 0, 20, -40 / 9])
    assert namespace['positions'].shape == (301, 1)
    assert path.blend_times[:, 0] == pytest.approx([0.268, 0.468, 0.098, 0.102], abs=6e-4)
    assert plan.duration == pytest.approx(2.5)
    assert code in (REPO / 'docs' / 'core.md').read_text()  # the same five lines
