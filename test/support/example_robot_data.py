"""
Real robot descriptions from example-robot-data (the Pinocchio team's set of URDFs).

Not a dependency: :func:`example_robot_data_urdfs` downloads its wheel once with pip
(``pip download --no-deps example-robot-data==VERSION``, pure Python, the same for every
platform), extracts only the URDF files below into pytest's cache directory
(``.pytest_cache/d/example-robot-data-<version>/``, ignored by git) and deletes the
archive; later runs read the cache. Where pip cannot get it, the tests that need the
files skip, saying why. The URDFs name meshes by ``package://`` paths; Pinocchio's
``buildModelFromXML`` does not load meshes, so none are extracted.
"""

from __future__ import annotations

from pathlib import Path
import subprocess
import sys
import tempfile
import zipfile

import pytest

VERSION = '6.0.0'
#: The URDFs used, relative to ``robots/`` in the wheel's data.
FILES = {
    'panda': 'panda_description/urdf/panda.urdf',
    'ur10': 'ur_description/urdf/ur10_robot.urdf',
}
_DATA = 'cmeel.prefix/share/example-robot-data/robots/'
#: pip's time limit for the ~130 MB download (s).
DOWNLOAD_TIMEOUT = 600


def _download(target: Path) -> str:
    """Fetch the wheel and extract :data:`FILES` into ``target``; return '' or why not."""
    with tempfile.TemporaryDirectory() as folder:
        try:
            result = subprocess.run(
                [sys.executable, '-m', 'pip', 'download', '--quiet', '--no-deps',
                 '--disable-pip-version-check', '--dest', folder,
                 f'example-robot-data=={VERSION}'], capture_output=True, text=True,
                timeout=DOWNLOAD_TIMEOUT)
        except subprocess.TimeoutExpired:
            return f'pip download example-robot-data=={VERSION} took over {DOWNLOAD_TIMEOUT} s'
        wheels = list(Path(folder).glob('example_robot_data-*.whl'))
        if result.returncode != 0 or not wheels:
            tail = ' '.join(result.stderr.strip().splitlines()[-1:])
            return f'pip could not download example-robot-data=={VERSION}: {tail}'
        partial = target.with_name(target.name + '.partial')
        with zipfile.ZipFile(wheels[0]) as wheel:
            names = set(wheel.namelist())
            missing = [relative for relative in FILES.values() if _DATA + relative not in names]
            if missing:
                return f'example-robot-data {VERSION} has no {missing}'
            for relative in FILES.values():
                destination = partial / relative
                destination.parent.mkdir(parents=True, exist_ok=True)
                destination.write_bytes(wheel.read(_DATA + relative))
        partial.rename(target)  # whole or not at all: a killed run leaves no half cache
    return ''


def urdfs_in(cache: Path) -> dict[str, Path] | str:
    """
    Return the paths of :data:`FILES` under ``cache`` (fetching them once), or why not.

    :param cache: pytest's cache data folder (``.pytest_cache/d``) or any other folder.
    """
    target = cache / f'example-robot-data-{VERSION}' / 'robots'
    if not target.is_dir():
        target.parent.mkdir(parents=True, exist_ok=True)
        reason = _download(target)
        if reason:
            return reason
    return {name: target / relative for name, relative in FILES.items()}


def example_robot_data_urdfs(config: pytest.Config) -> dict[str, Path]:
    """
    Return the paths of the URDFs in :data:`FILES` by short name; skip if unavailable.

    :param config: pytest's config (``request.config``), whose cache holds the files.
    """
    cache = getattr(config, 'cache', None)
    if cache is None:
        pytest.skip("the example-robot-data URDFs need pytest's cache directory "
                    '(cacheprovider)')
    found = urdfs_in(Path(cache.mkdir(f'example-robot-data-{VERSION}')).parent)
    if isinstance(found, str):
        pytest.skip(found)
    return found
