"""
Real robot descriptions from example-robot-data (the Pinocchio team's set of URDFs).

Not a dependency: :func:`example_robot_data_urdfs` downloads its wheel once with pip
(``pip download --no-deps example-robot-data==VERSION``, pure Python, the same for every
platform; :func:`pip_cache.fetch_once`), extracts only the URDF files below into pytest's
cache directory (``.pytest_cache/d/example-robot-data-<version>/``, ignored by git) and
deletes the archive; later runs read the cache. Where pip cannot get it, the tests that
need the files skip, saying why. The URDFs name meshes by ``package://`` paths;
Pinocchio's ``buildModelFromXML`` does not load meshes, so none are extracted. The
benchmarks, outside pytest, read the same cache (:func:`benchmark_urdfs`).
"""

from __future__ import annotations

from pathlib import Path
import zipfile

from pip_cache import cache_folder, fetch_once
import pytest

VERSION = '6.0.0'
#: The URDFs used, relative to ``robots/`` in the wheel's data.
FILES = {
    'panda': 'panda_description/urdf/panda.urdf',
    'ur10': 'ur_description/urdf/ur10_robot.urdf',
}
_DATA = 'cmeel.prefix/share/example-robot-data/robots/'
#: pytest's cache data directory of this repository (``.pytest_cache/d``).
REPO_CACHE = Path(__file__).resolve().parents[2] / '.pytest_cache' / 'd'


def _extract(wheel_path: Path, folder: Path) -> str:
    """Write :data:`FILES` from the wheel into ``folder``; return '' or why not."""
    with zipfile.ZipFile(wheel_path) as wheel:
        names = set(wheel.namelist())
        missing = [relative for relative in FILES.values() if _DATA + relative not in names]
        if missing:
            return f'example-robot-data {VERSION} has no {missing}'
        for relative in FILES.values():
            destination = folder / relative
            destination.parent.mkdir(parents=True, exist_ok=True)
            destination.write_bytes(wheel.read(_DATA + relative))
    return ''


def urdfs_in(cache: Path) -> dict[str, Path] | str:
    """
    Return the paths of :data:`FILES` under ``cache`` (fetching them once), or why not.

    :param cache: pytest's cache data folder (``.pytest_cache/d``) or any other folder.
    """
    target = cache / f'example-robot-data-{VERSION}' / 'robots'
    reason = fetch_once(target, f'example-robot-data=={VERSION}', 'example_robot_data-*.whl',
                        _extract)
    if reason:
        return reason
    return {name: target / relative for name, relative in FILES.items()}


def example_robot_data_urdfs(config: pytest.Config) -> dict[str, Path]:
    """
    Return the paths of the URDFs in :data:`FILES` by short name; skip if unavailable.

    :param config: pytest's config (``request.config``), whose cache holds the files.
    """
    folder = cache_folder(config, f'example-robot-data-{VERSION}',
                          'the example-robot-data URDFs')
    found = urdfs_in(folder.parent)
    if isinstance(found, str):
        pytest.skip(found)
    return found


def benchmark_urdfs(what: str) -> dict[str, Path] | None:
    """
    Return the paths of :data:`FILES` in :data:`REPO_CACHE`, fetched once as the tests do.

    For a benchmark outside pytest: where they cannot be fetched, print that ``what`` is
    skipped and why (``== what: skipped, why``) and return None.
    """
    found = urdfs_in(REPO_CACHE)
    if isinstance(found, str):
        print(f'== {what}: skipped, {found}')
        return None
    return found
