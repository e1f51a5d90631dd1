"""A full disk for a test: a small tmpfs mounted in a mount namespace of the command's own
(`unshare -m`, or `unshare -rm` for a user without the right), so nothing outside sees it.
Where the machine allows neither, the test is skipped with the reason."""

import functools
import os
import subprocess

import pytest


@functools.cache
def _unshare():
    """The unshare command that may mount here, or None."""
    for cmd in (["unshare", "-m"], ["unshare", "-rm"]):
        try:
            p = subprocess.run(
                [*cmd, "sh", "-c", "mount -t tmpfs -o size=64k tmpfs /mnt"], capture_output=True, timeout=30
            )
        except (OSError, subprocess.TimeoutExpired):
            continue
        if p.returncode == 0:
            return cmd
    return None


def run(tmp_path, script, size="2m", timeout=300):
    """The shell `script` run with $D a fresh tmpfs of `size` (its mount point under tmp_path),
    $HERE the repository root; the CompletedProcess (text). Skips where mounting is not allowed."""
    cmd = _unshare()
    if cmd is None:
        pytest.skip("no full-disk test here: this machine allows no tmpfs mount in a namespace (unshare -m, -rm)")
    mount = tmp_path / "full"
    mount.mkdir(exist_ok=True)
    wrapper = f'mount -t tmpfs -o size={size} tmpfs "$D" || exit 97\n{script}'
    env = dict(os.environ, D=str(mount), HERE=str(os.getcwd()))
    return subprocess.run([*cmd, "sh", "-c", wrapper], capture_output=True, text=True, timeout=timeout, env=env)
