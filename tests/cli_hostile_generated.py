#!/usr/bin/env python3
"""The generated hostile-input suite (docs/security.md, "Budgets"): each module of tests/hostile_cases/ writes
its inputs at run time (no large binaries in the repository) and runs `visbuf` on them. Every run is capped:

  - killed past 60 s of wall time, or as soon as its resident memory passes 2 GiB (read from /proc while it
    runs, and from the kernel's peak afterwards): either is a failure;
  - a crash (a signal, exit code 134 / 139, a sanitizer's exit code) is a failure;
  - the case's own check says whether the result is a clean error (exit 1, a message naming the problem) or a
    correct result.

A case module defines `cases(ctx)`, yielding (name, function) pairs; `ctx` is the Context below.

Usage: cli_hostile_generated.py --visbuf build/tools/visbuf [--work DIR] [--module NAME] [-k SUBSTRING]
"""
import argparse
import importlib.util
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

TIME_LIMIT_S = 60.0
RSS_LIMIT_KIB = 2 * 1024 * 1024  # 2 GiB


class Outcome:
    def __init__(self, cmd, code, stdout, stderr, seconds, rss_kib, killed):
        self.cmd, self.code, self.stdout, self.stderr = cmd, code, stdout, stderr
        self.seconds, self.rss_kib, self.killed = seconds, rss_kib, killed

    @property
    def text(self):
        return self.stderr.decode(errors="replace")

    def describe(self):
        return (f"\n  command: {' '.join(self.cmd)}\n  exit {self.code}, {self.seconds:.2f} s, "
                f"{self.rss_kib // 1024} MiB peak{', killed: ' + self.killed if self.killed else ''}"
                f"\n  stderr: {self.text.strip()[-1500:]}")


def _rss_kib(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0


def run(cmd, cwd, time_limit=TIME_LIMIT_S, rss_limit_kib=RSS_LIMIT_KIB, stdin=None):
    """Runs cmd in cwd with the caps above; returns an Outcome (code < 0: killed by that signal)."""
    os.makedirs(cwd, exist_ok=True)
    with tempfile.TemporaryFile() as so, tempfile.TemporaryFile() as se:
        start = time.monotonic()
        proc = subprocess.Popen(cmd, stdin=stdin if stdin is not None else subprocess.DEVNULL, stdout=so,
                                stderr=se, cwd=cwd)
        killed = ""
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            if time.monotonic() - start > time_limit:
                killed = f"still running after {time_limit:.0f} s"
            elif _rss_kib(proc.pid) > rss_limit_kib:
                killed = f"resident memory over {rss_limit_kib // 1024} MiB"
            if killed:
                proc.kill()
                pid, status, usage = os.wait4(proc.pid, 0)
                break
            time.sleep(0.005)
        seconds = time.monotonic() - start
        proc.returncode = os.waitstatus_to_exitcode(status)
        so.seek(0)
        se.seek(0)
        return Outcome(cmd, proc.returncode, so.read(), se.read(), seconds, usage.ru_maxrss, killed)


class Context:
    def __init__(self, visbuf, work, repo):
        self.visbuf, self.work, self.repo = visbuf, work, repo
        self.failures = []
        self.count = 0

    def folder(self, case):
        """A fresh, empty folder for one case."""
        root = os.path.join(self.work, re.sub(r"[^A-Za-z0-9_.-]", "_", case))
        shutil.rmtree(root, ignore_errors=True)
        os.makedirs(root)
        return root

    def visbuf_run(self, args, cwd, **kw):
        return run([self.visbuf, *args], cwd, **kw)

    def fail(self, case, what, outcome=None):
        text = f"FAIL {case}: {what}" + (outcome.describe() if outcome is not None else "")
        self.failures.append(text)
        print(text, flush=True)

    def _capped(self, case, outcome):
        if outcome.killed:
            self.fail(case, outcome.killed, outcome)
            return False
        if outcome.rss_kib >= RSS_LIMIT_KIB:
            self.fail(case, f"peak RSS {outcome.rss_kib} KiB >= 2 GiB", outcome)
            return False
        return True

    def expect_error(self, case, outcome, pattern):
        """A clean refusal: exit 1, stderr matching `pattern` (a regular expression), within the caps."""
        self.count += 1
        if not self._capped(case, outcome):
            return False
        if outcome.code != 1:
            crash = " (a crash)" if outcome.code < 0 or outcome.code > 2 else ""
            self.fail(case, f"exit code {outcome.code}, expected 1{crash}", outcome)
            return False
        if not re.search(pattern, outcome.text):
            self.fail(case, f"stderr does not match /{pattern}/", outcome)
            return False
        last = outcome.text.strip().splitlines()[-1] if outcome.text.strip() else ""
        print(f"ok   {case}: exit 1 in {outcome.seconds:.2f} s, {outcome.rss_kib // 1024} MiB: {last[:160]}",
              flush=True)
        return True

    def expect_ok(self, case, outcome, check=None):
        """A correct result: exit 0 within the caps, and `check()` (when given) returns None or a failure text."""
        self.count += 1
        if not self._capped(case, outcome):
            return False
        if outcome.code != 0:
            self.fail(case, f"exit code {outcome.code}, expected 0", outcome)
            return False
        problem = check() if check else None
        if problem:
            self.fail(case, problem, outcome)
            return False
        print(f"ok   {case}: exit 0 in {outcome.seconds:.2f} s, {outcome.rss_kib // 1024} MiB", flush=True)
        return True

    def expect_clean(self, case, outcome, pattern=None):
        """Either a clean refusal matching `pattern` or a success: never a crash, a hang or a memory blow-up."""
        if outcome.code == 0:
            return self.expect_ok(case, outcome)
        return self.expect_error(case, outcome, pattern or r"error")


def load_modules(folder):
    modules = []
    for name in sorted(os.listdir(folder)):
        if name.endswith(".py") and not name.startswith("_"):
            spec = importlib.util.spec_from_file_location(f"hostile_cases.{name[:-3]}", os.path.join(folder, name))
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
            modules.append((name[:-3], module))
    return modules


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--visbuf", required=True, help="the visbuf program")
    parser.add_argument("--work", default=None, help="scratch folder (default: a temporary one, removed)")
    parser.add_argument("-k", default="", help="run only the cases whose name contains this")
    parser.add_argument("--module", default=None, help="run only this module of hostile_cases/")
    args = parser.parse_args()
    scratch = None
    if args.work:
        work = os.path.abspath(args.work)
        shutil.rmtree(work, ignore_errors=True)
        os.makedirs(work)
    else:
        work = scratch = tempfile.mkdtemp(prefix="visbuf_hostile_gen_")
    ctx = Context(os.path.abspath(args.visbuf), work, os.path.dirname(here))
    sys.path.insert(0, here)
    try:
        for module_name, module in load_modules(os.path.join(here, "hostile_cases")):
            if args.module is not None and module_name != args.module:
                continue
            for name, case in module.cases(ctx):
                full = f"{module_name}.{name}"
                if args.k in full:
                    try:
                        case()
                    except Exception as e:  # a broken generator is a failure, not a skipped case
                        ctx.fail(full, f"the case raised {type(e).__name__}: {e}")
    finally:
        if scratch:
            shutil.rmtree(scratch, ignore_errors=True)
    print(f"{ctx.count} passed, {len(ctx.failures)} failed")
    return 1 if ctx.failures or ctx.count == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
