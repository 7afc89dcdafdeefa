#!/usr/bin/env python3
"""Builds the version-20, version-19 and version-12 GameController vectors of this folder (README.md, "Built vectors").

Written for this project from the public struct layouts (RoboCupGameControlData.h of the Humanoid Soccer League's
GameController, versions 20 and 19; HL_RoboCupGameControlData.h and hl_control_message.rs of the Humanoid League's,
version 12), independently of the Scala codec and the C decoder the vectors test. Run it from this folder:
python3 make-vectors.py
"""
import struct

SUBSTITUTE_V20 = 13
SUBSTITUTE_V19 = 11
SUBSTITUTE_V12 = 14

# Version 20's penalties by code (README.md lists the same names).
PENALTIES_V20 = ["none", "illegal positioning", "motion in set", "motion in stop", "local game stuck",
                 "incapable robot", "pick-up", "ball holding", "leaving the field", "playing with arms/hands",
                 "pushing", "cautioned", "sent off", "substitute"]


def v20(packet, state, first_half=1, stopped=0, set_play=0, kicking=12, secs=600, secondary=0,
        score=(0, 0), budget=(12000, 12000), players=None):
    """A version-20 packet: the 18-byte header version 19 has too, then two 70-byte TeamInfo with 3-byte RobotInfo.

    players: {(team, index): (penalty, secsTillUnpenalised, cautions)} for the entries that differ from the default
    (players 1 to 7 in the game, 8 to 20 substitutes)."""
    out = b"RGme" + struct.pack("<BBBBBBBBBB", 20, packet, 7, 0, stopped, 0, state, set_play, first_half, kicking)
    out += struct.pack("<hh", secs, secondary)
    assert len(out) == 18, len(out)
    for t, (number, colour, keeper_colour) in enumerate([(12, 0, 2), (7, 1, 3)]):
        team = struct.pack("<BBBBBBHH", number, colour, keeper_colour, 1, score[t], 0, 0, budget[t])
        for p in range(20):
            default = (0 if p < 7 else SUBSTITUTE_V20, 0, 0)
            team += struct.pack("<BBB", *(players or {}).get((t, p), default))
        assert len(team) == 70, len(team)
        out += team
    assert len(out) == 158, len(out)
    return out


def v19(packet, state, first_half=1, stopped=0, set_play=0, kicking=12, secs=600, secondary=0,
        score=(0, 0), budget=(12000, 12000), penalised=None):
    out = b"RGme" + struct.pack("<BBBBBBBBBB", 19, packet, 7, 0, stopped, 0, state, set_play, first_half, kicking)
    out += struct.pack("<hh", secs, secondary)
    for t, (number, colour, keeper_colour) in enumerate([(12, 0, 2), (7, 1, 3)]):
        out += struct.pack("<BBBBBBHH", number, colour, keeper_colour, 1, score[t], 0, 0, budget[t])
        for p in range(20):
            if penalised and penalised[0] == t and penalised[1] == p:
                out += struct.pack("<BBBB", *penalised[2:])
            else:
                out += struct.pack("<BBBB", 0 if p < 7 else SUBSTITUTE_V19, 0, 0, 0)
    assert len(out) == 198, len(out)
    return out


def v12_player(penalty=0, secs=0, warnings=0, yellow=0, red=0, keeper=0):
    return struct.pack("<BBBBBB", penalty, secs, warnings, yellow, red, keeper)


def v12(packet, state, first_half=1, kick_off=12, secondary_state=0, info=b"\0\0\0\0", secs=600, secondary=0,
        score=(0, 0), penalised=None):
    out = b"RGme" + struct.pack("<HBBBBBBB", 12, packet, 4, 0, state, first_half, kick_off, secondary_state)
    out += info + struct.pack("<BHhh", 0, 0xFFFF, secs, secondary)
    for t, (number, colour) in enumerate([(12, 0), (7, 1)]):
        out += struct.pack("<BBBBHB", number, colour, score[t], 0, 0, 0) + bytes(253) + v12_player()
        for p in range(11):
            if penalised and penalised[0] == t and penalised[1] == p:
                out += v12_player(*penalised[2:])
            else:
                out += v12_player(0 if p < 4 else SUBSTITUTE_V12, keeper=1 if p == 0 else 0)
    assert len(out) == 688, len(out)
    return out


V20_STATES = ["initial", "ready", "set", "playing", "finished"]


def v20_state(index, first_half):
    """One state of one half: packet numbers 1-5 in the first half, 11-15 in the second; the PLAYING packet with play
    stopped for a goal kick and a player penalised, as a real one may be."""
    packet = index + (1 if first_half else 11)
    kicking = 12 if first_half else 7
    if index == 1:
        return v20(packet, index, first_half, kicking=kicking, secondary=45)
    if index == 3:
        return v20(packet, index, first_half, stopped=1, set_play=5, kicking=7, secs=587, secondary=30,
                   score=(2, 1), budget=(11800, 11790), players={(0, 2): (10, 25, 0)})
    if index == 4:
        return v20(packet, index, first_half, kicking=kicking, secs=0, score=(2, 1), budget=(11000, 10990))
    return v20(packet, index, first_half, kicking=kicking)


VECTORS = {
    "v19-initial.bin": v19(1, 0),
    "v19-ready.bin": v19(2, 1, secondary=45),
    "v19-set.bin": v19(3, 2, budget=(11950, 11940)),
    "v19-playing.bin": v19(4, 3, stopped=1, set_play=5, kicking=7, secs=587, secondary=30, score=(2, 1),
                           budget=(11800, 11790), penalised=(0, 2, 9, 25, 1, 1)),
    "v19-finished.bin": v19(5, 4, first_half=0, kicking=7, secs=0, score=(2, 1), budget=(11000, 10990)),
    "v12-initial.bin": v12(1, 0),
    "v12-ready.bin": v12(2, 1, secondary=30),
    "v12-set.bin": v12(3, 2),
    "v12-playing.bin": v12(4, 3, kick_off=7, secondary_state=4, info=b"\x07\0\0\0", secs=587, score=(2, 1),
                           penalised=(0, 2, 31, 25, 1, 1, 0, 0)),
    "v12-finished.bin": v12(5, 4, first_half=0, kick_off=7, secs=0, score=(2, 1)),
    # Every penalty of version 20 at once: team[0]'s player index i has penalty code i (0 to 13) and 10 + i seconds
    # left (0 for none and the two without a clock: sent off, substitute); the cautioned player has 1 caution.
    "v20-penalties.bin": v20(21, 3, players={
        (0, i): (i, 0 if i in (0, 12, 13) else 10 + i, 1 if i == 11 else 0) for i in range(len(PENALTIES_V20))}),
}
for i, name in enumerate(V20_STATES):
    VECTORS[f"v20-{name}.bin"] = v20_state(i, first_half=1)
    VECTORS[f"v20-{name}-second-half.bin"] = v20_state(i, first_half=0)

if __name__ == "__main__":
    for name, data in VECTORS.items():
        with open(name, "wb") as f:
            f.write(data)
