"""
Real robot descriptions that nobody here wrote: the URDFs of pybullet's ``pybullet_data``.

pybullet is not a dependency: :func:`pybullet_urdfs` downloads its source distribution
once with pip (``pip download --no-deps --no-binary :all: pybullet==PYBULLET``, the same
for every Python; :func:`pip_cache.fetch_once`), extracts only the URDF files below into
pytest's cache directory (``.pytest_cache/d/pybullet_data-<version>/``, ignored by git)
and deletes the archive; later runs read the cache. Where pip cannot get it (no network,
no index), the tests that need the files skip, saying why.
"""

from __future__ import annotations

from pathlib import Path
import tarfile

from pip_cache import cache_folder, fetch_once
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


def _extract(archive_path: Path, folder: Path) -> str:
    """Write :data:`FILES` from the sdist into ``folder``; return '' or why not."""
    wanted = {_DATA + relative: relative for relative in FILES.values()}
    with tarfile.open(archive_path) as archive:
        for member in archive.getmembers():
            relative = wanted.pop(member.name, None)
            if relative is None or not member.isfile():
                continue
            destination = folder / relative
            destination.parent.mkdir(parents=True, exist_ok=True)
            destination.write_bytes(archive.extractfile(member).read())
    if wanted:
        return f'pybullet {PYBULLET} has no {sorted(wanted.values())}'
    return ''


def pybullet_urdfs(config: pytest.Config) -> dict[str, Path]:
    """
    Return the paths of the URDFs in :data:`FILES` by short name; skip if unavailable.

    :param config: pytest's config (``request.config``), whose cache holds the files.
    """
    folder = cache_folder(config, f'pybullet_data-{PYBULLET}', 'the pybullet URDFs')
    target = folder / 'pybullet_data'
    reason = fetch_once(target, f'pybullet=={PYBULLET}', 'pybullet-*.tar.gz', _extract,
                        ('--no-binary', ':all:'))
    if reason:
        pytest.skip(reason)
    return {name: target / relative for name, relative in FILES.items()}
