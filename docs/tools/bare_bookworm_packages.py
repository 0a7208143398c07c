#!/usr/bin/python3
"""How many packages, and how many MB of downloads, `apt-get install --no-install-recommends PACKAGE...` takes
on a bare Debian bookworm (debootstrap's minbase: the priority-required packages, apt, and what they depend on).

    docs/tools/bare_bookworm_packages.py build-essential cmake ...

Runs `apt-get --simulate` against a dpkg status holding only that base, taken from this machine's own status
(which must hold the base, as any bookworm install does) and its apt lists for the priorities and sizes.
Changes nothing on the machine; needs no root.
"""
import os
import re
import subprocess
import sys
import tempfile


def stanzas(text):
    return [s for s in text.split("\n\n") if s.strip()]


def field(stanza, name):
    m = re.search(r"^%s: (.*)$" % name, stanza, re.M)
    return m.group(1) if m else None


def main(packages):
    if not packages:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    avail = subprocess.run(["apt-cache", "dumpavail"], capture_output=True, text=True, check=True).stdout
    priority, size = {}, {}
    for s in stanzas(avail):
        name, version = field(s, "Package"), field(s, "Version")
        if field(s, "Priority"):
            priority.setdefault(name, field(s, "Priority"))
        if field(s, "Size"):
            size[(name, version)] = (int(field(s, "Size")), int(field(s, "Installed-Size") or 0))

    installed, provides = {}, {}
    with open("/var/lib/dpkg/status") as f:
        for s in stanzas(f.read()):
            if not (field(s, "Status") or "").endswith(" installed"):
                continue
            name = field(s, "Package")
            installed[name] = s
            for p in (field(s, "Provides") or "").split(","):
                if p.strip():
                    provides.setdefault(p.split()[0], name)

    def depends(s):
        out = []
        for f in ("Pre-Depends", "Depends"):
            for group in (field(s, f) or "").split(","):
                for alt in group.split("|"):
                    n = alt.strip().split(" ")[0].split(":")[0]
                    if n in installed or n in provides:
                        out.append(n if n in installed else provides[n])
                        break
        return out

    # minbase: the required packages and apt, closed under Depends and Pre-Depends.
    todo = [p for p in installed if priority.get(p) == "required"] + ["apt"]
    base = set()
    while todo:
        p = todo.pop()
        if p not in base:
            base.add(p)
            todo += depends(installed[p])

    with tempfile.TemporaryDirectory() as tmp:
        status = os.path.join(tmp, "status")
        with open(status, "w") as f:
            f.write("\n\n".join(installed[p] for p in sorted(base)) + "\n\n")
        sim = subprocess.run(["apt-get", "--simulate", "-o", "Dir::State::status=" + status, "install",
                              "--no-install-recommends", *packages], capture_output=True, text=True)
    if sim.returncode != 0:
        print(sim.stderr.strip(), file=sys.stderr)
        return 1
    count, download, unpacked = 0, 0, 0
    for line in sim.stdout.splitlines():
        m = re.match(r"Inst (\S+) (?:\[\S+\] )?\((\S+)", line)
        if m:
            count += 1
            d, i = size.get((m.group(1).split(":")[0], m.group(2)), (0, 0))
            download, unpacked = download + d, unpacked + i
    print(f"{count} packages, {download / 1e6:.0f} MB to download, {unpacked / 1e3:.0f} MB installed "
          f"(on a bare bookworm of {len(base)} packages)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
