"""Hostile submissions (docs/programs.md, "Confinement"): `make grade` on a folder of one correct
program and programs that try to forge their verdict, harm the grader or other submissions,
outlive their runs, reach the network, stop the grading, exhaust the machine or read the
grader's environment, beside entries with odd names. The grading must complete, rank the correct
submission first among the submissions, and leave nothing changed or running.

Each hostile program is written here, with the paths it attacks baked in, as a student would
after reading the lab's source. Skipped where bwrap cannot make a sandbox (the grading then
refuses, which test_unconfinable_machine_refuses_without_unconfined checks).
"""
import csv
import ctypes
import hashlib
import json
import os
import re
import shutil
import socket
import subprocess
import threading
import time

import pytest

from build_path import BUILD
from entry_point import ROOT, run_tool

# $0 of every shell a hostile program leaves running, to find them after
TOKEN = "psweep-hostile-4711"


def bwrap_works() -> bool:
    if not shutil.which("bwrap"):
        return False
    return subprocess.run(["bwrap", "--unshare-all", "--ro-bind", "/usr", "/usr", "--symlink",
                           "usr/bin", "/bin", "--symlink", "usr/lib", "/lib", "--symlink",
                           "usr/lib64", "/lib64", "/bin/true"],
                          capture_output=True).returncode == 0


pytestmark = pytest.mark.skipif(not bwrap_works(), reason="bwrap cannot make a sandbox here")


def digest(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def leftover_processes() -> list[str]:
    found = []
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            cmdline = (open(f"/proc/{pid}/cmdline", "rb").read().replace(b"\0", b" ")
                       .decode(errors="replace"))
        except OSError:
            continue
        if TOKEN in cmdline and "pytest" not in cmdline:
            found.append(f"{pid}: {cmdline}")
    return found


class Listener:
    """A TCP listener on 127.0.0.1 that counts the connections it accepts."""

    def __init__(self):
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(16)
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.connections = 0
        self.stop = False
        self.thread = threading.Thread(target=self.serve, daemon=True)
        self.thread.start()

    def serve(self):
        while not self.stop:
            try:
                conn, _ = self.sock.accept()
                self.connections += 1
                conn.close()
            except OSError:
                pass

    def close(self):
        self.stop = True
        self.thread.join()
        self.sock.close()


def write(folder, name, body, mode=0o755):
    path = folder / name
    path.write_text(body)
    path.chmod(mode)
    return path


# The timing scene of the quick grading, and the seed a course once published for it.
TIMING_SCENE = {"N": 40, "L": 2000, "r": 1, "S": 20}
PUBLISHED_SEED = 7


def quick_config(folder, **timing_scene):
    """configs/grade.json on two judging scenes and a small timing scene; its seed drawn per
    grading, as grade.json's is, unless given."""
    config = json.loads((ROOT / "configs" / "grade.json").read_text())
    config["judging"]["scenes"] = [s for s in config["judging"]["scenes"]
                                   if s["file"] in ("scenes/corner.in", "scenes/head_on.in")]
    config["judging"]["T"] = [1]
    # Busy runs counted: on a shared machine every timed run could be busy and leave no time to
    # grade (their exclusion: test_grade_rules.py and test_harness_psweep.py).
    config["timing"].update(scene={**TIMING_SCENE, **timing_scene}, repetitions=2, warmup=1,
                            T=[1], quiet={"busy_runs": "count"})
    path = folder / "grade_quick.json"
    path.write_text(json.dumps(config))
    return path


def stored_answer() -> tuple[str, str]:
    """The published timing scene's first particle (x and y as %.8f) and psim's answer to it, as
    a cheat would compute them in advance."""
    header = "".join(f"{TIMING_SCENE[k]}\n" for k in "NLrS") + "perf\n"
    scene = subprocess.run([str(BUILD / "psim"), "--write-scene", "/dev/stdout", "--seed",
                            str(PUBLISHED_SEED)], input=header, capture_output=True, text=True,
                           check=True).stdout
    answer = subprocess.run([str(BUILD / "psim"), "--engine", "brute"], input=scene,
                            capture_output=True, text=True, check=True).stdout
    x, y = (float(v) for v in scene.splitlines()[5].split()[1:3])
    return f"{x:.8f} {y:.8f}", answer


def lookup(path):
    """plain_allpairs built to print, when timed, the answer stored after its own bytes if its
    scene is the published one, and to do no work otherwise (CHECK_CHEAT_STORED)."""
    key, answer = stored_answer()
    path.write_bytes((BUILD / "check_programs" / "stored").read_bytes()
                     + f"\n__STORED__\n{key}\n{answer}".encode())
    path.chmod(0o755)
    return path


# plain_allpairs behind a cache of answers in a SysV segment keyed by a hash of its input.
CACHER = r"""
#define main plain_allpairs_main
#include "plain_allpairs.c"
#undef main
#include <sys/shm.h>
#include <unistd.h>
static char in[1 << 20], out[8 << 20];
int main(void) {
  size_t n = fread(in, 1, sizeof in, stdin);
  key_t key = 5381;
  for (size_t i = 0; i < n; ++i) key = key * 33 + in[i];
  int id = shmget(key & 0x7fffffff, sizeof out, 0600);
  if (id >= 0) {
    char* stored = shmat(id, NULL, 0);
    if (stored != (void*)-1 && stored[0]) {
      fputs(stored, stdout);
      return 0;
    }
  }
  FILE* f = fopen("scene", "w");
  fwrite(in, 1, n, f);
  fclose(f);
  const int real_out = dup(1);
  freopen("scene", "r", stdin);
  freopen("answer", "w", stdout);
  char* plain[] = {"cacher", NULL};
  const int status = plain_allpairs_main(1, plain);
  fflush(stdout);
  f = fopen("answer", "r");
  const size_t m = fread(out, 1, sizeof out - 1, f);
  write(real_out, out, m);
  id = shmget(key & 0x7fffffff, sizeof out, IPC_CREAT | 0600);
  char* segment = id >= 0 ? shmat(id, NULL, 0) : (void*)-1;
  if (segment != (void*)-1) {
    memcpy(segment, out, m + 1);
    fprintf(stderr, "cached\n");
  } else {
    perror("shmget");
  }
  return status;
}
"""

# plain_allpairs after 200 threads of its own have started and ended.
THREADED = r"""
#include <pthread.h>
#define main plain_allpairs_main
#include "plain_allpairs.c"
#undef main
static void* nothing(void* arg) { return arg; }
int main(void) {
  pthread_t team[200];
  pthread_attr_t attr;
  pthread_attr_init(&attr);
  pthread_attr_setstacksize(&attr, 64 << 10);
  for (int i = 0; i < 200; ++i)
    if (pthread_create(&team[i], &attr, nothing, NULL) != 0) {
      perror("pthread_create");
      return 1;
    }
  for (int i = 0; i < 200; ++i) pthread_join(team[i], NULL);
  char* plain[] = {"threaded", NULL};
  return plain_allpairs_main(1, plain);
}
"""


def compile_c(path, source):
    """`source`, which includes tests/reference/plain_allpairs.c, built as a student would."""
    c = path.with_suffix(".c")
    c.write_text(source)
    subprocess.run(["gcc", "-O2", "-pthread", "-I", str(ROOT / "tests" / "reference"), "-o",
                    str(path), str(c), "-lm"], check=True)
    c.unlink()


# The run users psweep takes as root (harness/run/run_user.hpp): the range, and the one below
# `nobody` where a user namespace maps no such ids.
RUN_USERS = [range(0x7f000000, 0x7f000000 + 1024), range(65534 - 1024, 65534)]


def run_users_processes() -> list[str]:
    found = []
    for pid in os.listdir("/proc"):
        try:
            uid = os.stat(f"/proc/{pid}").st_uid
        except OSError:
            continue
        if pid.isdigit() and any(uid in users for users in RUN_USERS):
            found.append(f"{pid}: uid {uid}")
    return found


# The two tiers of confinement (docs/programs.md, "Confinement"): bwrap's namespaces, and, where a
# container refuses them (emulated by build/without_namespaces), Landlock and seccomp.
TIERS = {"bwrap": [], "landlock+seccomp": [str(BUILD / "without_namespaces")]}


def landlock_abi() -> int:
    libc = ctypes.CDLL(None, use_errno=True)
    return max(libc.syscall(444, None, 0, 1), 0)  # landlock_create_ruleset(..., VERSION)


def skip_without_tier(tier: str) -> None:
    """Skips a test of the second tier where the kernel offers no Landlock."""
    if tier == "landlock+seccomp" and landlock_abi() < 1:
        pytest.skip("the kernel offers no Landlock: the second tier cannot work here")


@pytest.fixture(scope="module", params=list(TIERS))
def hostile(request, tmp_path_factory):
    skip_without_tier(request.param)
    root = tmp_path_factory.mktemp("hostile")
    folder = root / "submissions"
    folder.mkdir()
    out = root / "out"
    outside = root / "outside.txt"
    outside.write_text("the grader's own file\n")
    psim = BUILD / "psim"
    shutil.copy(BUILD / "plain_allpairs", folder / "correct")
    listener = Listener()
    victims = {"psim": psim, "correct": folder / "correct", "outside": outside}
    before = {name: digest(path) for name, path in victims.items()}
    # Forge: replace psim, exec it, write into the repository, the results and another
    # submission, then print what psim printed.
    write(folder, "forger", f"""#!/bin/sh
cp /bin/true {psim} 2>/dev/null; printf '#!/bin/sh\\necho exact\\n' > {psim} 2>/dev/null
echo forged > {ROOT}/forged-by-a-submission 2>/dev/null
mkdir -p {out} 2>/dev/null; echo forged > {out}/scoreboard.md 2>/dev/null
echo forged > {folder}/correct 2>/dev/null
cat {outside} >&2 2>/dev/null; echo appended >> {outside} 2>/dev/null
if [ -x {psim} ]; then exec {psim} --engine brute; fi
echo 'no psim to borrow' >&2; exit 1
""")
    # Outlive: children, a double fork, a setsid daemon that later rewrites the scoreboard, a
    # CPU burner; then the right answer, borrowed from nowhere: it fails.
    write(folder, "lingerer", f"""#!/bin/sh
for i in 1 2 3 4 5 6 7 8; do sh -c 'sleep 3600; :' {TOKEN} & done
( ( sh -c 'while :; do :; done' {TOKEN} ) & )
setsid sh -c 'sleep 3; echo daemon > {out}/scoreboard.md; sleep 3600; :' {TOKEN} &
exit 0
""")
    # UDP, which Landlock does not cover: where there is no network namespace, the seccomp
    # filter's refusal of every socket but AF_UNIX is the only barrier.
    datagrams = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    datagrams.bind(("127.0.0.1", 0))
    datagrams.setblocking(False)
    write(folder, "networker", f"""#!/usr/bin/python3
import socket, sys
for host in ("127.0.0.1", "1.1.1.1"):
    try:
        socket.create_connection((host, {listener.port} if host == "127.0.0.1" else 53), 2)
        print("connected to", host, file=sys.stderr)
    except OSError as err:
        print(host, err, file=sys.stderr)
try:
    socket.socket(socket.AF_INET, socket.SOCK_DGRAM).sendto(
        b"datagram", ("127.0.0.1", {datagrams.getsockname()[1]}))
    print("sent a datagram", file=sys.stderr)
except OSError as err:
    print("udp", err, file=sys.stderr)
sys.exit(1)
""")
    # Chains of setsid, fork and exit: each link hands the next to psweep after it listed them.
    write(folder, "chainer", f"""#!/bin/sh
export CHAIN='setsid sh -c "$CHAIN" {TOKEN} & exit 0'
for i in 1 2 3 4 5 6; do sh -c "$CHAIN" {TOKEN} & done
exit 0
""")
    write(folder, "killer", "#!/bin/sh\nkill -STOP $PPID; kill -9 $PPID; kill -9 -1\n"
                            "echo 'still here' >&2; exit 1\n")
    write(folder, "hog", "#!/usr/bin/python3\nimport sys\nb = bytearray(4 << 30)\n"
                         "print('allocated 4 GiB', file=sys.stderr)\nsys.exit(1)\n")
    write(folder, "snoop", "#!/bin/sh\necho \"secret=[$GRADER_SECRET] home=$HOME pwd=$(pwd)\" >&2"
                           "\nexit 1\n")
    # Through the descriptors it inherits (runs.csv was one): a forged row for itself and a
    # crashed one for the correct submission into each, then the same line into every other.
    write(folder, "rowwriter", """#!/usr/bin/python3
import os, sys
for name in os.listdir("/proc/self/fd"):
    if int(name) > 2:
        try:
            os.write(int(name), b"rowwriter,forged-row,ok,exact,0.0004\\ncorrect,forged-row,crashed\\n")
            print("wrote into", name, os.readlink("/proc/self/fd/" + name), file=sys.stderr)
        except OSError:
            pass
sys.exit(1)
""")
    # Its stdin is the scene every later run and check reads: truncated through /proc.
    write(folder, "truncator", "#!/bin/sh\n: > /proc/self/fd/0 && echo 'truncated the scene' >&2"
                               "\nexit 1\n")
    # 512 MiB of disk reserved behind a few bytes of output (past RLIMIT_FSIZE: KEEP_SIZE).
    write(folder, "fallocator", """#!/usr/bin/python3
import ctypes, sys
libc = ctypes.CDLL(None, use_errno=True)
print("0 0 1 1 0 0")
sys.stdout.flush()
libc.fallocate(1, 1, ctypes.c_long(0), ctypes.c_long(512 << 20))
""")
    # Memory RLIMIT_DATA does not count: a shared mapping, a stack raised to its hard limit.
    write(folder, "shmapper", """#!/usr/bin/python3
import mmap, sys
try:
    m = mmap.mmap(-1, 3 << 30, flags=mmap.MAP_SHARED | mmap.MAP_ANONYMOUS)
    print("mapped 3 GiB", file=sys.stderr)
except OSError as err:
    print("no 3 GiB mapping:", err, file=sys.stderr)
sys.exit(1)
""")
    write(folder, "stacker", """#!/usr/bin/python3
import resource, sys
soft, hard = resource.getrlimit(resource.RLIMIT_STACK)
try:
    resource.setrlimit(resource.RLIMIT_STACK, (resource.RLIM_INFINITY, resource.RLIM_INFINITY))
    print("raised the stack to unlimited", file=sys.stderr)
except (ValueError, OSError) as err:
    print(f"stack kept at {soft}:{hard}:", err, file=sys.stderr)
sys.exit(1)
""")
    # Disk the folders' limits did not count: /dev/shm and /dev themselves.
    # Disk the folders' limits did not count: /dev/shm (its files each within RLIMIT_FSIZE, as
    # many as it holds), /dev itself and the sandbox's root.
    write(folder, "shmfiller", """#!/usr/bin/python3
import os, sys
shm = os.statvfs("/dev/shm")
print("/dev/shm holds", shm.f_blocks * shm.f_frsize >> 20, "MiB", file=sys.stderr)
for path in ("/dev/shm/fill", "/dev/fill", "/fill"):
    try:
        open(path, "wb").close()
        print(path, "written", file=sys.stderr)
    except OSError as err:
        print(path + ":", err.strerror, file=sys.stderr)
sys.exit(1)
""")
    # Kernel memory in empty files: a million of them held 864 MB (100,000 tried here).
    write(folder, "filefiller", """#!/usr/bin/python3
import os, sys
made = 0
try:
    while made < 100000:
        open(f"f{made}", "w").close()
        made += 1
except OSError as err:
    print("stopped:", err.strerror, file=sys.stderr)
print("made", made, "files", file=sys.stderr)
sys.exit(1)
""")
    # Answers kept between runs or past the memory limit (issue 57): a SysV segment, memfds
    # filled with fallocate, a host's Unix socket outside every rule.
    write(folder, "sysv", """#!/usr/bin/python3
import ctypes, sys
libc = ctypes.CDLL(None, use_errno=True)
segment = libc.shmget(0, 1 << 20, 0o1600)  # IPC_PRIVATE, IPC_CREAT | 0600
print("segment", segment, "errno", ctypes.get_errno(), file=sys.stderr)
sys.exit(1)
""")
    write(folder, "memfder", """#!/usr/bin/python3
import os, sys
held = 0
try:
    for i in range(12):
        fd = os.memfd_create(f"m{i}")
        os.posix_fallocate(fd, 0, 256 << 20)
        held += 256
except OSError as err:
    print("stopped:", err.strerror, file=sys.stderr)
print("held", held, "MiB", file=sys.stderr)
sys.exit(1)
""")
    host_socket = root / "host.sock"
    unix = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    unix.bind(str(host_socket))
    os.chmod(host_socket, 0o777)
    os.chmod(root, 0o755)
    unix.listen(4)
    unix.setblocking(False)
    write(folder, "unixer", f"""#!/usr/bin/python3
import socket, sys
try:
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.connect("{host_socket}")
    s.sendall(b"reached the host")
    print("wrote to the host's socket", file=sys.stderr)
except OSError as err:
    print("unix:", err, file=sys.stderr)
sys.exit(1)
""")
    # A cache of answers kept in a SysV segment keyed by its input: every repetition after the
    # first printed the stored answer (Gradescope's score 100, "15.8x the fastest engine").
    compile_c(folder / "cacher", CACHER)
    # Sleeping threads kept past its run by a detached survivor, against the next runs of the same
    # user, then a correct classmate that needs 200 threads.
    write(folder, "survivor", """#!/usr/bin/python3
import os, sys, threading, time
if os.fork() == 0:
    os.setsid()
    if os.fork() == 0:
        threading.stack_size(64 << 10)
        for i in range(250):
            try:
                threading.Thread(target=time.sleep, args=(3600,), daemon=True).start()
            except RuntimeError:
                break
        time.sleep(3600)
    os._exit(0)
time.sleep(1)
sys.exit(1)
""")
    compile_c(folder / "threaded", THREADED)
    # Every CPU for a T = 1 run, then only the CPUs it was not given.
    write(folder, "widener", """#!/usr/bin/python3
import os, sys
given = sorted(os.sched_getaffinity(0))
os.sched_setaffinity(0, range(os.cpu_count()))
print("given", given, "asked for all, got", sorted(os.sched_getaffinity(0)), file=sys.stderr)
try:
    os.sched_setaffinity(0, set(range(os.cpu_count())) - set(given))
    print("moved to", sorted(os.sched_getaffinity(0)), file=sys.stderr)
except OSError as err:
    print("elsewhere:", err.strerror, file=sys.stderr)
sys.exit(1)
""")
    # Idle when timed, or a stored answer to the published timing scene (the grading draws
    # another).
    shutil.copy(BUILD / "check_programs" / "idle", folder / "idler")
    lookup(folder / "lookup")
    # Odd names, each graded or said.
    for name in ("with space", "new\nline", "é-accent", "-dash", "bob{x}"):
        shutil.copy(BUILD / "plain_allpairs", folder / name)
    (folder / "inside-link").symlink_to("correct")
    (folder / "psim-link").symlink_to(psim)
    (folder / "a-folder").mkdir()
    write(folder, "not-executable", "#!/bin/sh\n", mode=0o644)
    write(folder, "no-interpreter", "#!/usr/bin/no-such-interpreter\n")
    write(folder, "crlf", "#!/bin/sh\r\nexit 0\r\n")
    elf = bytearray((BUILD / "plain_allpairs").read_bytes())
    elf[18:20] = (183).to_bytes(2, "little")  # EM_AARCH64
    (folder / "arm64").write_bytes(bytes(elf))
    (folder / "arm64").chmod(0o755)
    with open(folder / "sparse", "wb") as f:  # 2 GB that takes 4 KB of disk
        f.truncate(2 << 30)
    (folder / "sparse").chmod(0o755)
    env = dict(os.environ, GRADER_SECRET="s3cr3t-of-the-grader")
    done = subprocess.run(
        TIERS[request.param] + [
            "/usr/bin/python3", "-m", "analysis", "grade", str(folder), "--out", str(out),
            "--config", str(quick_config(root)), "--psweep", str(BUILD / "psweep")],
        capture_output=True, text=True, timeout=600, cwd=ROOT, env=env)
    time.sleep(4)  # the daemon's moment to rewrite the scoreboard, had it survived
    listener.close()
    assert (out / "scoreboard.csv").is_file(), done.stderr[-3000:]
    with open(out / "scoreboard.csv", newline="") as f:
        board = {row["name"]: row for row in csv.DictReader(f)}
    try:
        datagram = datagrams.recv(64)
    except BlockingIOError:
        datagram = b""
    datagrams.close()
    try:
        reached, _ = unix.accept()
    except BlockingIOError:
        reached = None
    unix.close()
    yield {"done": done, "board": board, "out": out, "victims": victims, "before": before,
           "listener": listener, "datagram": datagram, "unix_reached": reached is not None,
           "folder": folder, "tier": request.param}
    for pid in leftover_processes():  # never leave them to spoil the next test's timings
        os.kill(int(pid.split(":")[0]), 9)


def test_the_grading_completes_and_ranks_the_correct_submission_first(hostile):
    done, board = hostile["done"], hostile["board"]
    assert done.returncode == 0, done.stderr
    copies = {"correct", "with space", "new\\nline", "é-accent", "-dash", "inside-link", "bob{x}"}
    # plain_allpairs too, one behind a SysV cache that is refused, one after 200 threads
    correct = copies | {"cacher", "threaded"}
    programs = sorted((int(r["rank"]), name) for name, r in board.items() if r["kind"] == "program")
    assert programs[0][1] in correct, programs
    exact = {name for name, r in board.items() if r["verdict"] == "exact"}
    assert correct <= exact, board
    assert not exact & {"forger", "lingerer", "chainer", "networker", "killer", "hog", "snoop", "rowwriter",
                        "sysv", "memfder", "unixer", "survivor",
                        "truncator", "fallocator", "idler", "lookup", "shmapper", "stacker",
                        "shmfiller", "filefiller", "widener"}


def test_no_submission_earns_by_doing_less_when_timed(hostile):
    board, out = hostile["board"], hostile["out"]
    meta = json.loads((out / "meta.json").read_text())
    assert meta["timing_seed_source"] == "drawn" and meta["timing_seed"] != PUBLISHED_SEED
    assert f"timing scene seed {meta['timing_seed']}, drawn for this grading" in \
        hostile["done"].stderr
    with open(out / "grades.csv", newline="") as f:
        grades = {g["name"]: g for g in csv.DictReader(f)}
    for name in ("idler", "lookup"):  # right when judged, idle when timed (no stored answer fits)
        row = board[name]
        assert row["verdict"] == "violations" and row["scene"].startswith("N=40"), row
        assert ("its final state is not the one it prints in print mode for the same scene"
                in row["first_violation"]), row
        assert float(grades[name]["speed_score"]) == 0 and grades[name]["best_s"] == ""
        assert float(grades[name]["judging_score"]) == float(grades["correct"]["judging_score"])
        assert int(row["rank"]) > int(board["correct"]["rank"])


def test_a_pinned_timing_seed_is_said_to_let_a_stored_answer_through(tmp_path):
    folder = tmp_path / "submissions"
    folder.mkdir()
    shutil.copy(BUILD / "plain_allpairs", folder / "correct")
    lookup(folder / "lookup")
    out = tmp_path / "out"
    done = subprocess.run(
        ["/usr/bin/python3", "-m", "analysis", "grade", str(folder), "--out", str(out),
         "--config", str(quick_config(tmp_path, seed=PUBLISHED_SEED)), "--psweep",
         str(BUILD / "psweep")], capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert (f"timing scene seed {PUBLISHED_SEED}, pinned by the config: a submission can carry "
            "the answer to a pinned scene") in done.stderr
    meta = json.loads((out / "meta.json").read_text())
    assert meta["timing_seed"] == PUBLISHED_SEED and meta["timing_seed_source"] == "pinned"
    # psim's answer is the model's, and so what the program prints in print mode: a pinned scene
    # cannot tell it from work done. Only a drawn seed can (the test above).
    with open(out / "scoreboard.csv", newline="") as f:
        board = {row["name"]: row for row in csv.DictReader(f)}
    assert board["lookup"]["verdict"] == "exact", board["lookup"]


def test_a_program_whose_repetitions_differ_is_nondeterministic(tmp_path):
    # Right in its first timed run and its judging run, then another final state.
    count = tmp_path / "count"
    racer = write(tmp_path, "racer", f"""#!/bin/sh
n=$(cat {count} 2>/dev/null || echo 0); echo $((n + 1)) > {count}
if [ "$n" -lt 2 ]; then exec {BUILD / "plain_allpairs"}; fi
{BUILD / "plain_allpairs"} | sed '$ s/ [0-9]* [0-9]*$/ 9 9/'
""")
    config = tmp_path / "racer.json"
    config.write_text(json.dumps({
        "base": {"engine": "racer", "N": 40, "L": 2000, "r": 1, "S": 20, "seed": 7, "T": 1},
        "programs": {"racer": {"command": [str(racer)]}}, "repetitions": 3, "warmup": 0,
        "pin": "none", "timeout_s": 30}))
    done = subprocess.run([str(BUILD / "psweep"), str(config), "--out", str(tmp_path / "out"),
                           "--unconfined"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    with open(tmp_path / "out" / "runs.csv", newline="") as f:
        checks = [(r["check"], r["check_detail"]) for r in csv.DictReader(f)]
    assert checks[0][0] == "exact", checks
    for verdict, detail in checks[1:]:
        assert verdict == "violations", checks
        assert detail.startswith("nondeterministic: repetition ") and \
            "prints another final state than the judged repetition of the same scene: " \
            "particle 39: " in detail, detail


def test_nothing_outside_the_runs_changed(hostile):
    for name, path in hostile["victims"].items():
        assert digest(path) == hostile["before"][name], f"{name} changed"
    assert not (ROOT / "forged-by-a-submission").exists()
    # grade's own table, a line per row: neither the forger nor the daemon wrote it
    scoreboard = (hostile["out"] / "scoreboard.md").read_text()
    assert scoreboard.startswith("# Scoreboard: ")
    table = [line for line in scoreboard.splitlines() if line.startswith("|")]
    assert table[0].startswith("| rank | name |") and len(table) == len(hostile["board"]) + 2
    assert scoreboard.endswith(" its report: each scene and T, the check's findings, its points "
                               "and its timing\n")


def test_no_descriptor_of_the_grader_reached_a_submission(hostile):
    for path in hostile["out"].rglob("*"):
        if path.is_file() and path.suffix in (".csv", ".md", ".json", ".html"):
            assert "forged-row" not in path.read_text(errors="replace"), path
    rowwriter = hostile["board"]["rowwriter"]
    assert rowwriter["verdict"] == "failed" and "wrote into" not in rowwriter["first_violation"]
    truncator = hostile["board"]["truncator"]
    assert truncator["verdict"] == "failed", truncator
    assert "truncated the scene" not in truncator["first_violation"]
    assert "cannot create /proc/self/fd/0" in truncator["first_violation"]


def test_limits_count_shared_memory_the_stack_dev_shm_and_the_cpus(hostile):
    board = hostile["board"]
    for name in ("shmapper", "stacker", "shmfiller", "filefiller", "widener"):
        assert board[name]["verdict"] == "failed", board[name]
    assert "no 3 GiB mapping" in board["shmapper"]["first_violation"]
    assert "stack kept at 8388608:8388608" in board["stacker"]["first_violation"]
    shm = board["shmfiller"]["first_violation"]
    if hostile["tier"] == "bwrap":  # a /dev/shm of its own, disk_mib in size; the rest read-only
        assert "/dev/shm holds 256 MiB" in shm and "/dev/fill: Read-only file system" in shm, shm
        assert "/dev/shm/fill written" in shm and "/fill: Read-only file system" in shm, shm
    else:  # the host's /dev/shm and /: Landlock lets it write neither
        for path in ("/dev/shm/fill", "/dev/fill", "/fill"):
            assert f"{path}: Permission denied" in shm, shm
    files = board["filefiller"]["first_violation"]
    if hostile["tier"] == "bwrap":  # its folder holds a file per 4 KiB of disk_mib (256 MiB)
        assert "stopped: No space left on device" in files and "made 65535 files" in files, files
    else:  # a folder of the host's, walked while the run lives (harness/run/folder_limit.hpp)
        assert files.startswith("crashed: its folder held more than "), files
        assert "disk_mib = 256 MiB): killed" in files or "disk_mib = 256 MiB: killed" in files, files
    # "No space left on device" in a program's words is its verdict: the grading went on.
    assert hostile["done"].returncode == 0
    # Its binding is cut to the CPU it was given, as a cpuset cuts it; elsewhere is refused.
    widener = board["widener"]["first_violation"]
    given = re.search(r"given (\[\d+\])", widener).group(1)
    assert f"asked for all, got {given}" in widener, widener
    assert "elsewhere: Invalid argument" in widener and "moved" not in widener, widener


def test_disk_reserved_beyond_the_output_limit_is_freed(hostile):
    fallocator = hostile["board"]["fallocator"]
    assert fallocator["verdict"] == "failed"
    assert "reserved with fallocate" in fallocator["first_violation"]
    held = max(p.stat().st_blocks * 512 for p in hostile["out"].rglob("*") if p.is_file())
    assert held < 16 << 20, held


def test_no_process_of_a_submission_is_alive(hostile):
    assert leftover_processes() == []
    assert run_users_processes() == []


def test_no_answer_is_cached_between_runs_and_threads_are_the_runs_own(hostile):
    # The cacher's speed is tried through the Gradescope zip, on a longer timing scene
    # (test_gradescope_autograder.py); here, what its user left.
    board = hostile["board"]
    with open("/proc/sysvipc/shm") as f:
        owners = [int(line.split()[7]) for line in f.readlines()[1:]]
    assert not [uid for uid in owners if any(uid in users for users in RUN_USERS)]
    # The survivor's 250 threads ended with its run: the classmate had its 200.
    assert board["survivor"]["verdict"] == "failed", board["survivor"]
    assert board["threaded"]["verdict"] == "exact", board["threaded"]


def test_no_connection_reached_the_listener(hostile):
    assert hostile["listener"].connections == 0
    assert hostile["datagram"] == b""
    assert not hostile["unix_reached"]
    unixer = hostile["board"]["unixer"]["first_violation"]
    assert "unix:" in unixer and "wrote" not in unixer, unixer


def test_nothing_is_shared_between_runs_or_held_past_the_memory_limit(hostile):
    board = hostile["board"]
    sysv, memfds = board["sysv"]["first_violation"], board["memfder"]["first_violation"]
    # Refused in both tiers: a SysV segment or a memfd is memory no limit counts.
    assert "segment -1 errno 1" in sysv, sysv
    assert "stopped: Operation not permitted" in memfds and "held 0 MiB" in memfds, memfds
    networker = hostile["board"]["networker"]
    assert networker["verdict"] == "failed"
    assert "connected" not in networker["first_violation"]


def test_the_hostile_rows_say_what_happened(hostile):
    board = hostile["board"]
    forger = board["forger"]["first_violation"]
    assert board["forger"]["verdict"] == "failed", forger
    if hostile["tier"] == "bwrap":  # psim is not in the sandbox at all
        assert "no psim to borrow" in forger
    else:  # psim is there, and Landlock lets it execute nothing outside the system's folders
        assert f"exec: {BUILD / 'psim'}: Permission denied" in forger, forger
    assert "the grader's own file" not in forger
    assert board["killer"]["verdict"] == "failed" and "still here" in board["killer"]["first_violation"]
    assert board["hog"]["verdict"] == "failed" and "MemoryError" in board["hog"]["first_violation"]
    snoop = board["snoop"]["first_violation"]
    assert "secret=[]" in snoop, snoop
    folder = "/box" if hostile["tier"] == "bwrap" else "/tmp/psweep-stage-"
    assert f"home={folder}" in snoop and f"pwd={folder}" in snoop, snoop
    assert board["lingerer"]["verdict"] in ("malformed", "failed", "violations")


def test_odd_entries_get_rows_that_say_what_they_are(hostile):
    board, done = hostile["board"], hostile["done"]
    assert "outside the submissions folder: not graded" in board["psim-link"]["first_violation"]
    assert "a folder without a Makefile: not graded" in board["a-folder"]["first_violation"]
    assert "not executable" in board["not-executable"]["first_violation"]
    assert ("its interpreter /usr/bin/no-such-interpreter (the #! line) does not exist"
            in board["no-interpreter"]["first_violation"])
    assert "inside-link" in board and board["inside-link"]["verdict"] == "exact"
    assert "Windows line endings" in board["crlf"]["first_violation"]
    assert ("a program for AArch64 (arm64), and this machine is x86-64"
            in board["arm64"]["first_violation"])
    assert "more than a submission may be (64 MiB): not graded" in board["sparse"]["first_violation"]
    scoreboard = (hostile["out"] / "scoreboard.md").read_text()
    assert "| new\\nline |" in scoreboard and "| é-accent |" in scoreboard
    assert "grade: psim-link: a symlink to" in done.stderr
    reports = {p.name for p in (hostile["out"] / "reports").iterdir()}
    assert {"new_line.md", "_dash.md", "with_space.md", "_-accent.md"} <= reports


def test_without_bwrap_the_grading_falls_back_to_landlock_and_says_so(tmp_path):
    folder = tmp_path / "submissions"
    folder.mkdir()
    shutil.copy(BUILD / "plain_allpairs", folder / "correct")
    env = dict(os.environ, PATH=str(tmp_path))  # no bwrap on PATH
    out = tmp_path / "o"
    done = subprocess.run(
        ["/usr/bin/python3", "-m", "analysis", "grade", str(folder), "--out", str(out),
         "--config", str(quick_config(tmp_path)), "--psweep", str(BUILD / "psweep")],
        capture_output=True, text=True, timeout=120, cwd=ROOT, env=env)
    assert done.returncode == 0, done.stderr
    assert ("psweep: programs run confined by landlock+seccomp, without namespaces (bubblewrap "
            "(bwrap) is not installed: apt-get install bubblewrap)") in done.stderr
    meta = json.loads((out / "timing" / "meta.json").read_text())
    assert meta["confinement"]["tool"] == "landlock+seccomp"
    with open(out / "scoreboard.csv", newline="") as f:
        assert {r["name"]: r["verdict"] for r in csv.DictReader(f)}["correct"] == "exact"


def psweep_programs(tmp_path, programs, *options, timeout_s=30, prefix=()):
    config = tmp_path / "progs.json"
    config.write_text(json.dumps({
        "base": {"engine": "brute", "N": 40, "L": 2000, "r": 1, "S": 20, "seed": 7, "T": 1},
        "sweep": {"engine": list(programs)}, "programs": programs, "repetitions": 1,
        "warmup": 0, "pin": "none", "timeout_s": timeout_s}))
    done = subprocess.run([*prefix, str(BUILD / "psweep"), str(config), "--out",
                           str(tmp_path / "out"), *options], capture_output=True, text=True,
                          timeout=120,
                          env=dict(os.environ, GRADER_SECRET="s3cr3t"))
    with open(tmp_path / "out" / "runs.csv", newline="") as f:
        rows = {r["engine"]: r for r in csv.DictReader(f)}
    return done, rows


def test_a_timed_out_run_leaves_nothing_alive_when_psweep_ends(tmp_path):
    hang = write(tmp_path, "hang", f"#!/bin/sh\nsetsid sh -c 'sleep 3600; :' {TOKEN} &\n"
                                   f"sh -c 'sleep 3600; :' {TOKEN} &\nsleep 3600\n")
    done, rows = psweep_programs(tmp_path, {"hang": {"command": [str(hang)]}}, timeout_s=1)
    assert done.returncode == 0, done.stderr
    assert leftover_processes() == []  # at once: the kill waited for the sandbox to be gone
    assert rows["hang"]["status"] == "timeout"


def test_limits_are_the_configs_and_unconfined_runs_as_before(tmp_path):
    burn = write(tmp_path, "burn", "#!/bin/sh\nwhile :; do :; done\n")
    env = write(tmp_path, "env", "#!/bin/sh\necho \"[$GRADER_SECRET] $MINE $(pwd)\" >&2; exit 1\n")
    programs = {"burn": {"command": [str(burn)], "limits": {"cpu_s": 1}},
                "env": {"command": [str(env)], "env": {"MINE": "given"}}}
    done, rows = psweep_programs(tmp_path, programs)
    assert done.returncode == 0, done.stderr
    assert rows["burn"]["status"] == "crashed" and "signal 24" in rows["burn"]["error"]
    assert "[] given /box" in rows["env"]["error"]
    meta = json.loads((tmp_path / "out" / "meta.json").read_text())
    assert meta["confinement"]["tool"] == "bwrap" and meta["confinement"]["sandbox_start_s"] > 0
    done, rows = psweep_programs(tmp_path, {"env": programs["env"]}, "--unconfined")
    assert done.returncode == 0, done.stderr
    assert f"[s3cr3t] given {os.getcwd()}" in rows["env"]["error"]


@pytest.mark.parametrize("tier", list(TIERS))
def test_a_confined_runs_rusage_is_the_programs_own(tmp_path, tier):
    # bwrap's sandbox init reaps the program and bwrap does not reap the init: runs.csv once
    # showed bwrap's own 0.007 s user for a 9.4 s run.
    skip_without_tier(tier)
    burn = write(tmp_path, "burn", "#!/usr/bin/python3\nimport time\nstart = time.process_time()"
                                   "\nwhile time.process_time() - start < 0.6:\n    pass\n")
    done, rows = psweep_programs(tmp_path, {"burn": {"command": [str(burn)]}}, prefix=TIERS[tier])
    assert done.returncode == 0, done.stderr
    assert float(rows["burn"]["user_s"]) + float(rows["burn"]["sys_s"]) >= 0.6, rows["burn"]
    assert int(rows["burn"]["max_rss_kb"]) > 4000, rows["burn"]  # python's, not sh's or bwrap's
