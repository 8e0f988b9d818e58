"""Running ROS nodes and launch files as subprocesses in tests, and reading their output: shared by
the startup-policy rostest (ebslam_msgs/test/startup_policy.py) and the system tests of ebslam_ros
(ebslam_ros/test/live_ebslam3d_system.py imports it from this folder).

Each process runs in a session of its own, so that stopping it (SIGINT, as Ctrl-C would, then
SIGKILL after a grace period) reaches every process roslaunch or rosrun started."""
import os
import signal
import subprocess
import tempfile
import time


def start(command, log):
    """Starts `command` in a new session, stdout and stderr to the open file `log`."""
    return subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                            start_new_session=True)


def stop(process, grace_s=10.0):
    """SIGINT to the process group, SIGKILL after grace_s [s]; nothing if it already ended."""
    if process is None or process.poll() is not None:
        return
    os.killpg(process.pid, signal.SIGINT)
    try:
        process.wait(timeout=grace_s)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        process.wait()


def run_until_exit(command, timeout_s):
    """(returncode, or None if still running after timeout_s [s] (then stopped), combined output)."""
    with tempfile.TemporaryFile() as log:
        process = start(command, log)
        try:
            code = process.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            stop(process)
            code = None
        log.seek(0)
        return code, log.read().decode(errors="replace")


def run_until_output(command, needle, timeout_s):
    """(found, still running when found, output): reads the output until `needle` appears, the
    process ends or timeout_s [s] pass; then stops the process."""
    with tempfile.NamedTemporaryFile() as log:
        process = start(command, log)
        deadline = time.monotonic() + timeout_s
        found = False
        while time.monotonic() < deadline:
            if needle in read(log.name):
                found = True
                break
            if process.poll() is not None:
                break
            time.sleep(0.2)
        running = process.poll() is None
        stop(process)
        return found, running, read(log.name)


def read(path):
    """The text of a log file ("" if it cannot be read)."""
    try:
        with open(path, errors="replace") as f:
            return f.read()
    except OSError:
        return ""


def problem_lines(text, levels=("ERROR", "FATAL"), died=True):
    """The lines of ROS output logged at one of `levels` ("[ERROR] ...", rosconsole's and
    rospy's format) and, with `died`, roslaunch's reports of a process that died."""
    tags = tuple(f"[{level}]" for level in levels)
    return [line.strip() for line in text.splitlines()
            if any(tag in line for tag in tags) or (died and "has died" in line)]
