"""
Real robot descriptions that nobody here wrote: the URDFs of pybullet's ``pybullet_data``.

pybullet is not a dependency: :func:`pybullet_urdfs` downloads its source distribution
once with pip (``pip download --no-deps --no-binary :all: pybullet==PYBULLET``, the same
for every Python), extracts only the URDF files below into pytest's cache directory
(``.pytest_cache/d/pybullet_data-<version>/``, ignored by git) and deletes the archive;
later runs read the cache. Where pip cannot get it (no network, no index), the tests that
need the files skip, saying why.
"""

from __future__ import annotations

from pathlib import Path
import subprocess
import sys
import tarfile
import tempfile

import pytest

PYBULLET = '3.2.7'
#: The URDFs used, relative to ``pybullet_data/`` (all xacro-free, meshes not needed).
FILES = {
    'panda': 'franka_panda/panda.urdf',
    'iiwa': 'kuka_iiwa/model.urdf',
    'iiwa_vr_limits': 'kuka_iiwa/model_vr_limits.urdf',
    'xarm6': 'xarm/xarm6_robot.urdf',
    'xarm6_gripper': 'xarm/xarm6_with_gripper.urdf',
    'husky': 'husky/husky.urdf',
    'r2d2': 'r2d2.urdf',
}
_DATA = f'pybullet-{PYBULLET}/examples/pybullet/gym/pybullet_data/'
#: pip's time limit for the ~80 MB download (s).
DOWNLOAD_TIMEOUT = 600


def _download(target: Path) -> str:
    """Fetch the sdist and extract :data:`FILES` into ``target``; return '' or why not."""
    with tempfile.TemporaryDirectory() as folder:
        try:
            result = subprocess.run(
                [sys.executable, '-m', 'pip', 'download', '--quiet', '--no-deps',
                 '--no-binary', ':all:', '--disable-pip-version-check', '--dest', folder,
                 f'pybullet=={PYBULLET}'], capture_output=True, text=True,
                timeout=DOWNLOAD_TIMEOUT)
        except subprocess.TimeoutExpired:
            return f'pip download pybullet=={PYBULLET} took over {DOWNLOAD_TIMEOUT} s'
        archives = list(Path(folder).glob('pybullet-*.tar.gz'))
        if result.returncode != 0 or not archives:
            tail = ' '.join(result.stderr.strip().splitlines()[-1:])
            return f'pip could not download pybullet=={PYBULLET}: {tail}'
        wanted = {_DATA + relative: relative for relative in FILES.values()}
        partial = target.with_name(target.name + '.partial')
        with tarfile.open(archives[0]) as archive:
            for member in archive.getmembers():
                relative = wanted.pop(member.name, None)
                if relative is None or not member.isfile():
                    continue
                destination = partial / relative
                destination.parent.mkdir(parents=True, exist_ok=True)
                destination.write_bytes(archive.extractfile(member).read())
        if wanted:
            return f'pybullet {PYBULLET} has no {sorted(wanted.values())}'
        partial.rename(target)  # whole or not at all: a killed run leaves no half cache
    return ''


def pybullet_urdfs(config: pytest.Config) -> dict[str, Path]:
    """
    Return the paths of the URDFs in :data:`FILES` by short name; skip if unavailable.

    :param config: pytest's config (``request.config``), whose cache holds the files.
    """
    cache = getattr(config, 'cache', None)
    if cache is None:
        pytest.skip("the pybullet URDFs need pytest's cache directory (cacheprovider)")
    target = Path(cache.mkdir(f'pybullet_data-{PYBULLET}')) / 'pybullet_data'
    if not target.is_dir():
        reason = _download(target)
        if reason:
            pytest.skip(reason)
    return {name: target / relative for name, relative in FILES.items()}
