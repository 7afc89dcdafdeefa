#!/usr/bin/env python3
"""firmware/port/qemu/footprint.py: the footprint of `make footprint` (docs/firmware.md, "Footprint").

The library's flash and static RAM on the CM-530, from the footprint stub (port/cm530/footprint.c: every public
function kept, nothing else; the stub's own bytes are reported apart), and the test robot's image apart, each
split by part from the linker's map; and the figures of the measurement program (port/qemu/measure.c) run in qemu
with -icount: the largest stack of each entry point and its instructions. Prints a table and writes
build/footprint.json (the bench suite reads its flat `figures`).

Usage: footprint.py <qemu> <build dir>
"""
import json
import re
import subprocess
import sys

BUILDS = [("stop-and-wait", "cm530"), ("selective-repeat-w4", "cm530-w4")]
MEASURES = [("stop-and-wait", "qemu"), ("selective-repeat-w4", "qemu-w4")]
ICOUNT_SHIFT = 3  # 8 ns per instruction: SysTick at 120 MHz reads about 0.96 ticks per instruction


def part_of(path):
    """Which part of the image an input file belongs to."""
    if "/obj/src/gs1500m.o" in path:
        return "gs1500m driver"
    if "/obj/src/" in path:
        return "library"
    if "/gen/naogateway/" in path:
        return "message descriptors"
    if "/pb/" in path:
        return "nanopb runtime"
    if "/obj/port/cm530/footprint.o" in path or "/footprint_keep.o" in path:
        return "stub"
    if "/obj/port/" in path:
        return "board port"
    if "/obj/testrobot/" in path or "/obj/port/qemu/measure.o" in path:
        return "program"
    return "libc, libgcc"


def sizes_from_map(map_path):
    """Flash and RAM bytes per part, from the input sections the linker kept."""
    flash, ram = {}, {}
    started = False
    pending = None
    entry = re.compile(r"^\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S+)")
    with open(map_path) as f:
        for line in f:
            if line.startswith("Linker script and memory map"):
                started = True
                continue
            if not started:
                continue
            m = re.match(r"^ (\.[\w.$]+|COMMON)(\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S+))?", line)
            if m:
                if m.group(2):
                    section, size, path = m.group(1), int(m.group(4), 16), m.group(5)
                else:
                    pending = m.group(1)
                    continue
            elif pending:
                m2 = entry.match(line)
                pending_section, pending = pending, None
                if not m2:
                    continue
                section, size, path = pending_section, int(m2.group(2), 16), m2.group(3)
            else:
                continue
            if size == 0 or section.startswith(".debug") or section.startswith(".comment") or section == ".stack":
                continue
            part = part_of(path)
            if section.startswith((".text", ".rodata", ".isr_vector", ".ARM")):
                flash[part] = flash.get(part, 0) + size
            elif section.startswith(".data"):
                flash[part] = flash.get(part, 0) + size
                ram[part] = ram.get(part, 0) + size
            elif section.startswith((".bss", ".noinit")) or section == "COMMON":
                ram[part] = ram.get(part, 0) + size
    return flash, ram


def section_sizes(size_tool, elf):
    out = subprocess.run([size_tool, "-A", elf], check=True, capture_output=True, text=True).stdout
    sizes = {}
    for line in out.splitlines():
        parts = line.split()
        if len(parts) >= 2 and parts[0].startswith(".") and parts[1].isdigit():
            sizes[parts[0]] = int(parts[1])
    return sizes


def measure(qemu, elf):
    out = subprocess.run([qemu, "-M", "netduino2", "-display", "none", "-monitor", "none", "-nodefaults",
                          "-serial", "null", "-semihosting-config", "enable=on,target=native",
                          "-icount", "shift=%d,sleep=off" % ICOUNT_SHIFT, "-kernel", elf],
                         capture_output=True, text=True, timeout=120)
    text = out.stdout + out.stderr  # semihosting writes to qemu's stderr
    figures = {}
    for line in text.splitlines():
        m = re.match(r"measure (\w+) insns=(\d+) stack=(\d+) bytes=(\d+)", line)
        if m:
            figures[m.group(1)] = {"instructions": int(m.group(2)), "stack": int(m.group(3)), "bytes": int(m.group(4))}
    if out.returncode != 0 or "measure: done" not in text:
        sys.exit("measurement failed (%s, exit %d):\n%s" % (elf, out.returncode, text))
    return figures


def image(size_tool, build, variant, program):
    """Flash and static RAM of one CM-530 image, with its parts."""
    elf = "%s/%s/%s.elf" % (build, variant, program)
    s = section_sizes(size_tool, elf)
    flash_parts, ram_parts = sizes_from_map("%s/%s/%s.map" % (build, variant, program))
    flash = s.get(".isr_vector", 0) + s.get(".text", 0) + s.get(".ARM.exidx", 0) + s.get(".data", 0)
    ram = s.get(".data", 0) + s.get(".bss", 0) + s.get(".noinit", 0) + s.get(".stack_guard", 0)
    return {"flash": flash, "static_ram": ram, "stack_reserved": s.get(".stack", 0),
            "flash_parts": flash_parts, "ram_parts": ram_parts}


def main():
    qemu, size_tool, build = sys.argv[1], sys.argv[2], sys.argv[3]
    result = {"builds": {}, "examples": {}, "entries": {}}
    for name, variant in MEASURES:
        result["entries"][name] = measure(qemu, "%s/%s/measure.elf" % (build, variant))
    for (name, variant) in BUILDS:
        stub = image(size_tool, build, variant, "footprint")
        entries = result["entries"][name]
        result["builds"][name] = {
            # the library: library + GS1500M driver + nanopb + descriptors + libc + board port, the stub apart
            "library_flash": stub["flash"] - stub["flash_parts"].get("stub", 0),
            "library_ram": stub["static_ram"] - stub["ram_parts"].get("stub", 0),
            "stack_max": max(e["stack"] for e in entries.values()),
            "keepalive_instructions": entries["keepalive"]["instructions"],
            "signed_keepalive_instructions": entries["keepalive_signed"]["instructions"],
            "stub_flash": stub["flash_parts"].get("stub", 0),
            "stub_ram": stub["ram_parts"].get("stub", 0),
            "stack_reserved": stub["stack_reserved"],
            "flash_parts": {k: v for k, v in stub["flash_parts"].items() if k != "stub"},
            "ram_parts": {k: v for k, v in stub["ram_parts"].items() if k != "stub"},
        }
        result["examples"][name] = image(size_tool, build, variant, "robot")

    # The bench suite's figures (src/test/scala/bench/FirmwareBench.scala), flat.
    w1, w4 = result["builds"]["stop-and-wait"], result["builds"]["selective-repeat-w4"]
    e1, e4 = result["examples"]["stop-and-wait"], result["examples"]["selective-repeat-w4"]
    entries = result["entries"]["stop-and-wait"]
    figures = {
        "firmware_library_flash_bytes_w1": w1["library_flash"],
        "firmware_library_flash_bytes_w4": w4["library_flash"],
        "firmware_library_static_ram_bytes_w1": w1["library_ram"],
        "firmware_library_static_ram_bytes_w4": w4["library_ram"],
        "firmware_example_flash_bytes_w1": e1["flash"],
        "firmware_example_flash_bytes_w4": e4["flash"],
        "firmware_example_static_ram_bytes_w1": e1["static_ram"],
        "firmware_example_static_ram_bytes_w4": e4["static_ram"],
    }
    for entry, e in entries.items():
        figures["firmware_stack_%s_bytes" % entry] = e["stack"]
    figures["firmware_stack_max_bytes"] = max(w1["stack_max"], w4["stack_max"])
    for entry, e in entries.items():
        figures["firmware_%s_instructions" % entry] = e["instructions"]
    figures["firmware_keepalive_instructions_w4"] = w4["keepalive_instructions"]
    figures["firmware_keepalive_signed_instructions_w4"] = w4["signed_keepalive_instructions"]
    result["figures"] = figures
    with open("%s/footprint.json" % build, "w") as f:
        json.dump(result, f, indent=2)

    print("The library on the CM-530 (STM32F103RE; arm-none-eabi-gcc, newlib-nano), measured with the footprint stub")
    print("%-22s %10s %12s %10s %11s %11s" % ("build", "flash (B)", "static RAM", "stack max", "keep-alive",
                                             "signed k-a"))
    for name, b in result["builds"].items():
        print("%-22s %10d %12d %10d %11d %11d" % (name, b["library_flash"], b["library_ram"], b["stack_max"],
                                                  b["keepalive_instructions"], b["signed_keepalive_instructions"]))
    for name, b in result["builds"].items():
        print("\nby part (%s)          flash (B)    RAM (B)" % name)
        for p in sorted(set(b["flash_parts"]) | set(b["ram_parts"])):
            print("  %-28s %10d %10d" % (p, b["flash_parts"].get(p, 0), b["ram_parts"].get(p, 0)))
        print("  %-28s %10d %10d" % ("(the stub itself, not counted)", b["stub_flash"], b["stub_ram"]))
    print("\nThe test robot's image (testrobot/robot.c), apart")
    print("%-24s %10s %14s %16s" % ("build", "flash (B)", "static RAM (B)", "program's part"))
    for name, b in result["examples"].items():
        print("%-24s %10d %14d %8d / %5d" % (name, b["flash"], b["static_ram"], b["flash_parts"].get("program", 0),
                                               b["ram_parts"].get("program", 0)))
    print("\nEntry points on the emulated Cortex-M3 (qemu netduino2, -icount shift=%d; stack by painting)" % ICOUNT_SHIFT)
    print("%-24s %-20s %12s %10s %8s" % ("build", "entry", "instructions", "stack (B)", "bytes"))
    for name, entries in result["entries"].items():
        for entry, e in entries.items():
            print("%-24s %-20s %12d %10d %8d" % (name, entry, e["instructions"], e["stack"], e["bytes"]))
    print("\nwritten to %s/footprint.json" % build)


if __name__ == "__main__":
    main()
