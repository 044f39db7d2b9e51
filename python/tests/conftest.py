"""Fixtures for the hapto module's tests: the build's `hapto` command, run in a subprocess, is
the reference every Python result is checked against (same columns, same numbers)."""

import csv
import io
import os
import subprocess

import numpy
import pytest


def pytest_configure(config):
    config.addinivalue_line("markers", "realtime: runs real servo threads on the wall clock")


class Cli:
    """The build's `hapto` command (HAPTO_EXECUTABLE, set by ctest)."""

    def __init__(self, executable):
        self.executable = executable

    def run(self, *args, check=True):
        r = subprocess.run([self.executable, *map(str, args)], capture_output=True, text=True)
        if check and r.returncode != 0:
            raise AssertionError("hapto %s: exit %d\n%s" % (" ".join(map(str, args)),
                                                            r.returncode, r.stderr))
        return r

    def csv(self, *args):
        """A command's CSV output (standard output) as a dict of column name -> list of text."""
        rows = list(csv.reader(io.StringIO(self.run(*args).stdout)))
        header, body = rows[0], rows[1:]
        return {name: [row[k] for row in body] for k, name in enumerate(header)}


@pytest.fixture(scope="session")
def cli():
    executable = os.environ.get("HAPTO_EXECUTABLE")
    assert executable, "HAPTO_EXECUTABLE names the build's hapto command (ctest sets it)"
    return Cli(executable)


@pytest.fixture(scope="session")
def source_dir():
    return os.environ["HAPTO_SOURCE_DIR"]


def as_numbers(texts, like):
    """CSV text as an array of the dtype of `like` (the Python column it is compared with)."""
    if like.dtype.kind in "iu":
        return numpy.array([int(t) for t in texts], dtype=like.dtype)
    return numpy.array([float(t) for t in texts], dtype=numpy.float64)
