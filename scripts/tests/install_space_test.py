#!/usr/bin/python3
"""The install space works on its own: installs the built workspace into a temporary prefix and starts
every launch file from there for a few seconds, asserting its main topics.

Install: `cmake --install <build>/<pkg> --prefix <tmp>` for every package already built in the
workspace (no rebuild; the install rules only copy). Run: a fresh environment that sees the prefix
and /usr only (ROS_PACKAGE_PATH=<tmp>/share:/usr/share, ...; no devel space, no source tree), a
roscore of its own on a free port, then `roslaunch <pkg> <file>` per case, waiting for one message on
each of the case's topics (rospy subscriber) and stopping the launch with SIGINT.
multi_machine.launch needs ssh to a robot: it is resolved (`roslaunch --nodes`) instead.

Usage: install_space_test.py WS_DIR [JUNIT_XML]   (exit 1 on a failure)
"""
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import textwrap
import time
import xml.etree.ElementTree as ET

PACKAGES = ["ebslam", "dasp", "edvs", "ebslam_ros_common", "ebslam_msgs", "dasp_ros", "edvs_driver", "ebslam_ros"]
STARTUP_S = 45.0  # per launch: nodelets load, the first messages arrive (2 shared cores)

# (name, package, launch file, args, topics each of which must carry a message)
CASES = [
    ("playback", "ebslam_ros", "playback.launch",
     ["bag:=$(find ebslam_ros)/data/session/session.bag", "loop:=true"],
     ["/ebslam/pose", "/camera/superpixels", "/edvs/event_image"]),
    ("demo_playback", "ebslam_ros", "demo_playback.launch", ["output_dir:=$(tmp)"],
     ["/ebslam/pose", "/camera/segmentation"]),
    ("playback_ebslam3d", "ebslam_ros", "playback.launch",
     ["bag:=$(find ebslam_ros)/data/dedvs_session/dedvs_session.bag", "loop:=true", "slam:=ebslam3d",
      "segmentation:=none"],
     ["/ebslam3d/pose", "/dedvs/depth_events", "/edvs/event_image"]),
    ("demo_playback3d", "ebslam_ros", "demo_playback3d.launch", ["output_dir:=$(tmp)"],
     ["/ebslam3d/pose", "/dedvs/depth_events"]),
    ("simulation", "ebslam_ros", "simulation.launch", ["speed:=2"],
     ["/ebslam/pose", "/ground_truth/pose", "/edvs/events"]),
    ("exploration", "ebslam_ros", "exploration.launch", ["speed:=2"],
     ["/ebslam/pose", "/ground_truth/pose", "/cmd_vel"]),
    ("ebslam3d_simulation", "ebslam_ros", "ebslam3d_simulation.launch", [],
     ["/ebslam3d/pose", "/dedvs/ground_truth/pose", "/dedvs/depth_events"]),
    ("dedvs_simulation", "ebslam_ros", "dedvs_simulation.launch", [],
     ["/dedvs/depth_events", "/dedvs/depth_registered/image_raw", "/dedvs/events"]),
    ("live", "ebslam_ros", "live.launch", ["camera:=false", "uri:=$(emulator)"],
     ["/edvs/events", "/edvs/event_image", "/ebslam/pose"]),
    ("demo", "ebslam_ros", "demo.launch", ["output_dir:=$(tmp)", "edvs_uri:=$(emulator)"],
     ["/camera/superpixels", "/camera/segmentation", "/edvs/events"]),
    ("record", "ebslam_ros", "record.launch", ["prefix:=$(tmp)/session"], []),
    ("simulated_localisation", "ebslam_ros", "simulated_localisation.launch", [],
     ["/pose", "/ground_truth/pose"]),
    ("folder_segmentation", "dasp_ros", "folder_segmentation.launch",
     ["folder:=$(find ebslam_ros)/data/sample_session", "loop:=true"],
     ["/camera/superpixels", "/camera/segmentation"]),
    ("edvs", "edvs_driver", "edvs.launch", ["uri:=$(emulator)"], ["/edvs/events", "/edvs/camera_info"]),
]
RESOLVE_ONLY = [("multi_machine", "ebslam_ros", "multi_machine.launch",
                 ["robot_address:=localhost", "robot_user:=robot", "robot_env_loader:=/bin/true"]),
                ("multi_machine_ebslam3d", "ebslam_ros", "multi_machine.launch",
                 ["robot_address:=localhost", "robot_user:=robot", "robot_env_loader:=/bin/true",
                  "slam:=ebslam3d"])]


def free_port():
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def install(ws, prefix):
    for package in PACKAGES:
        build = os.path.join(ws, "build", package)
        result = subprocess.run(["cmake", "--install", build, "--prefix", prefix],
                                capture_output=True, text=True, check=False)
        if result.returncode != 0:
            raise RuntimeError(f"install of {package} failed:\n{result.stdout[-2000:]}{result.stderr[-2000:]}")


def environment(ws, prefix, port):
    """Debian's ROS and the prefix, nothing of the workspace's devel space or sources."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("ROS_", "CMAKE_", "CATKIN_")) and k not in (
               "LD_LIBRARY_PATH", "PYTHONPATH", "PKG_CONFIG_PATH")}
    path = [p for p in env.get("PATH", "/usr/bin:/bin").split(":")
            if p and not p.startswith(ws) and "pyenv" not in p and "venv" not in p]
    env.update({
        "PATH": ":".join([os.path.join(prefix, "bin")] + path),
        "ROS_PACKAGE_PATH": f"{prefix}/share:/usr/share",
        "CMAKE_PREFIX_PATH": f"{prefix}:/usr",
        "LD_LIBRARY_PATH": os.path.join(prefix, "lib"),
        "PYTHONPATH": os.path.join(prefix, "lib", "python3", "dist-packages"),
        "ROS_MASTER_URI": f"http://localhost:{port}",
        "ROS_HOSTNAME": "localhost",
        "ROS_HOME": os.path.join(prefix, "ros_home"),
        "ROS_DISTRO": os.environ.get("ROS_DISTRO", "debian"),
        "ROSCONSOLE_STDOUT_LINE_BUFFERED": "1",
    })
    return env


WAITER = textwrap.dedent("""
    import sys, threading, rospy, rostopic
    topics = sys.argv[2:]
    deadline = float(sys.argv[1])
    rospy.init_node("install_space_waiter", anonymous=True, disable_signals=True)
    got, subs = set(), []
    start = rospy.get_time() if False else None
    import time
    end = time.monotonic() + deadline
    def make(topic):
        def callback(_msg):
            got.add(topic)
        return callback
    pending = list(topics)
    while time.monotonic() < end and len(got) < len(topics):
        for topic in list(pending):
            cls, real, _ = rostopic.get_topic_class(topic)
            if cls is not None:
                subs.append(rospy.Subscriber(real, cls, make(topic)))
                pending.remove(topic)
        time.sleep(0.2)
    missing = [t for t in topics if t not in got]
    print("MISSING " + " ".join(missing) if missing else "ALL")
    sys.exit(1 if missing else 0)
""")


def stop(process, timeout=20):
    if process.poll() is None:
        os.killpg(process.pid, signal.SIGINT)
        try:
            process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()


def substitute(arg, tmp, emulator):
    return arg.replace("$(tmp)", tmp).replace("$(emulator)", emulator)


def resolve_find(arg, env):
    while "$(find " in arg:
        start = arg.index("$(find ")
        end = arg.index(")", start)
        package = arg[start + 7:end]
        path = subprocess.run(["rospack", "find", package], env=env, capture_output=True, text=True,
                              check=True).stdout.strip()
        arg = arg[:start] + path + arg[end + 1:]
    return arg


def run_case(case, env, tmp, emulator_uri, logs):
    name, package, launch, args, topics = case
    args = [resolve_find(substitute(a, tmp, emulator_uri), env) for a in args]
    log_path = os.path.join(logs, f"{name}.log")
    with open(log_path, "w") as log:
        launch_process = subprocess.Popen(["roslaunch", package, launch] + args, env=env, stdout=log,
                                          stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                          start_new_session=True)
        try:
            if topics:
                waiter = subprocess.run(["/usr/bin/python3", "-c", WAITER, str(STARTUP_S)] + topics,
                                        env=env, capture_output=True, text=True, check=False,
                                        timeout=STARTUP_S + 30)
                ok = waiter.returncode == 0
                detail = waiter.stdout.strip() + waiter.stderr.strip()[-500:]
            else:
                time.sleep(5)
                ok = launch_process.poll() is None
                detail = "launch running" if ok else "launch ended"
            if launch_process.poll() not in (None, 0):
                ok = False
                detail += f"; roslaunch exited {launch_process.returncode}"
        finally:
            stop(launch_process)
    with open(log_path) as f:
        text = f.read()
    if not ok:
        detail += "\n" + text[-3000:]
    return ok, detail


def main():
    ws = os.path.abspath(sys.argv[1])
    junit = sys.argv[2] if len(sys.argv) > 2 else None
    results = []
    tmp = tempfile.mkdtemp(prefix="install_space_")
    prefix = os.path.join(tmp, "install")
    logs = os.path.join(tmp, "logs")
    os.makedirs(logs)
    core = emulator = None
    started = time.monotonic()
    try:
        install(ws, prefix)
        results.append(("install", True, f"{len(PACKAGES)} packages into {prefix}"))
        port = free_port()
        env = environment(ws, prefix, port)
        core = subprocess.Popen(["roscore", "-p", str(port)], env=env, stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL, start_new_session=True)
        time.sleep(2)
        # An emulated eDVS for the launch files with a driver: the installed emulator's event
        # generator over a pseudo-terminal link (the driver reconnects when a launch ends).
        link = os.path.join(tmp, "edvs_link")
        emulator = subprocess.Popen(
            ["rosrun", "edvs_driver", "edvs_emulator", "--link", link, "--rate", "20000",
             "--baud", "4000000"], env=env, stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL, start_new_session=True)
        emulator_uri = f"serial://{link}?format=E2"
        for case in CASES:
            ok, detail = run_case(case, env, tmp, emulator_uri, logs)
            results.append((case[0], ok, detail))
            print(f"install_space: {case[0]}: {'ok' if ok else 'FAILED'} {detail.splitlines()[0] if detail else ''}",
                  flush=True)
        for name, package, launch, args in RESOLVE_ONLY:
            result = subprocess.run(["roslaunch", "--nodes", package, launch] + args, env=env,
                                    capture_output=True, text=True, check=False)
            ok = result.returncode == 0 and result.stdout.strip() != ""
            results.append((name, ok, result.stdout.strip()[:200] + result.stderr[-1500:]))
            print(f"install_space: {name} (resolved only): {'ok' if ok else 'FAILED'}", flush=True)
    except Exception as error:  # noqa: BLE001 - every failure becomes a failed case
        results.append(("install_space", False, repr(error)))
        print(f"install_space: FAILED {error}", flush=True)
    finally:
        for process in (emulator, core):
            if process is not None:
                stop(process)
        print(f"install_space: {time.monotonic() - started:.0f} s", flush=True)
    if junit:
        suite = ET.Element("testsuite", name="install_space", tests=str(len(results)))
        for name, ok, detail in results:
            # Logs carry terminal colour codes: control characters XML cannot hold.
            detail = re.sub(r"[\x00-\x08\x0b\x0c\x0e-\x1f]", "", detail)
            case = ET.SubElement(suite, "testcase", classname="InstallSpace", name=name)
            if not ok:
                ET.SubElement(case, "failure", message=detail.splitlines()[0][:300] if detail else
                              "failed").text = detail
        ET.ElementTree(suite).write(junit, encoding="utf-8", xml_declaration=True)
    failed = [r for r in results if not r[1]]
    if not failed:
        shutil.rmtree(tmp, ignore_errors=True)
    else:
        print(f"install_space: logs kept in {logs}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
