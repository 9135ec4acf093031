"""A Python integration test's work folder and its main: the folder is made under the
system's temp folder unless the environment names one, and removed when every test passed
(a failing run's stays for a look; one the environment named is always kept)."""
import os
import shutil
import sys
import tempfile
import unittest
from pathlib import Path


def work_dir(env_var, prefix):
    named = os.environ.get(env_var)
    return Path(named) if named else Path(tempfile.mkdtemp(prefix=prefix))


def main(work, env_var):
    """unittest.main, then the folder removed on success; exits 1 on a failure."""
    print(f"work directory: {work}")
    result = unittest.main(verbosity=2, exit=False).result
    ok = result.wasSuccessful()
    if ok and not os.environ.get(env_var):
        shutil.rmtree(work, ignore_errors=True)
    sys.exit(0 if ok else 1)
