"""
Files out of a package's archive on the index, fetched once with pip into pytest's cache.

The real URDFs the tests use are in packages that are no dependency of this one
(:mod:`example_robot_data`, :mod:`pybullet_urdfs`): :func:`fetch_once` downloads the
package's archive with ``pip download --no-deps`` into a temporary folder, lets the caller
extract the files it wants into a folder beside the target, renames that folder to the
target (whole or not at all: a killed run leaves no half cache) and deletes the archive;
later runs find the target and fetch nothing. Where pip cannot get the archive, it says why,
for the tests that need the files to skip saying so.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
import subprocess
import sys
import tempfile

import pytest

#: pip's time limit for a download (s): the archives are 80-130 MB.
DOWNLOAD_TIMEOUT = 600


def cache_folder(config: pytest.Config, name: str, what: str) -> Path:
    """
    Return the folder ``name`` in pytest's cache data directory, made if need be.

    Skip the calling test, naming ``what`` needs it, where pytest runs without its cache
    (``-p no:cacheprovider``).

    :param config: pytest's config (``request.config``).
    """
    cache = getattr(config, 'cache', None)
    if cache is None:
        pytest.skip(f"{what} need pytest's cache directory (cacheprovider)")
    return Path(cache.mkdir(name))


def fetch_once(target: Path, requirement: str, archive_glob: str,
               extract: Callable[[Path, Path], str], pip_options: Sequence[str] = (),
               timeout: float = DOWNLOAD_TIMEOUT) -> str:
    """
    Fill the folder ``target`` from ``requirement``'s archive, unless it is there; return why not.

    :param target: the folder of the extracted files; nothing is fetched where it exists.
    :param requirement: what pip downloads, ``name==version`` (no dependencies).
    :param archive_glob: the downloaded archive's file name (``pybullet-*.tar.gz``).
    :param extract: ``extract(archive, folder)`` writes the files wanted from ``archive``
        into ``folder`` (to be renamed to ``target``); returns '' or why not.
    :param pip_options: more options for ``pip download`` (``--no-binary :all:``).
    :param timeout: pip's time limit (s).
    :returns: '' with ``target`` filled, or why it could not be.
    """
    if target.is_dir():
        return ''
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as folder:
        try:
            result = subprocess.run(
                [sys.executable, '-m', 'pip', 'download', '--quiet', '--no-deps',
                 '--disable-pip-version-check', *pip_options, '--dest', folder, requirement],
                capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return f'pip download {requirement} took over {timeout} s'
        archives = list(Path(folder).glob(archive_glob))
        if result.returncode != 0 or not archives:
            tail = ' '.join(result.stderr.strip().splitlines()[-1:])
            return f'pip could not download {requirement}: {tail}'
        partial = target.with_name(target.name + '.partial')
        reason = extract(archives[0], partial)
        if reason:
            return reason
        partial.rename(target)
    return ''
