#!/usr/bin/python3
"""Peak RSS of luxeld over one checkpointed, tiled bake (the daemon's path).

Starts LUXELD on 127.0.0.1:PORT with --checkpoint-interval 1 (and EXTRA
flags), bakes the bundled Cornell box through `luxel bake --server` at 2048²
with SG12, 8 samples and --device-memory-budget 200 (7 tiles, a checkpoint
of the whole atlas every second), stops the daemon with SIGTERM and prints
its peak RSS (wait4's ru_maxrss). A watchdog kills the daemon past 9 GiB.

    /usr/bin/python3 tests/bench/host_memory_daemon.py build/server/service/luxeld \
        build/client/luxel 50912 --host-memory-budget 0
"""
import os, signal, subprocess, sys, time, shutil
luxeld, luxel, port, extra = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
d = "/tmp/luxel_host_memory_daemon_data_" + port
shutil.rmtree(d, ignore_errors=True)
p = subprocess.Popen([luxeld, "--data-dir", d, "--listen", "127.0.0.1:" + port, "--checkpoint-interval", "1"] + extra,
                     stdout=subprocess.DEVNULL, stderr=open(d + ".log", "w"))
time.sleep(3)
srv = ["--server", "127.0.0.1:" + port]
b = subprocess.Popen([luxel, "bake", os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../scenes/cornell_box.gltf"), "--out", "/tmp/luxel_host_memory_daemon_out_" + port,
                      "--resolution", "2048", "--samples", "8", "--encoding", "sg12", "--denoise", "off",
                      "--device-memory-budget", "200"] + srv, stdout=open(d + ".bake", "w"), stderr=subprocess.STDOUT)
killed = False
while b.poll() is None:
    try:
        rss = int([l for l in open("/proc/%d/status" % p.pid) if l.startswith("VmRSS")][0].split()[1]) * 1024
    except Exception:
        rss = 0
    if rss > 9 * 2**30:
        p.kill(); killed = True; break
    time.sleep(0.1)
b.wait()
p.send_signal(signal.SIGTERM)
_, st, ru = os.wait4(p.pid, 0)
print("port", port, "bake rc", b.returncode, "killed", killed, "luxeld peak RSS GiB %.2f" % (ru.ru_maxrss / 2**20))
