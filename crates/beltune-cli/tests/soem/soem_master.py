"""An independent EtherCAT master (SOEM, through pysoem) against `beltune virtual-drive`.

Run by crates/beltune-cli/tests/soem.rs inside a network namespace pair it creates:

    python soem_master.py IFACE dc|nodc CYCLES CYCLE_NS

It drives the virtual drive as a user of SOEM would and prints one JSON object with what it saw
(identity, SDO answers and abort codes, SDO information, complete access, the AL states and
status codes, the cyclic exchange, the watchdog and its recovery, the bus brought down). The Rust
test judges the numbers against the CiA 301 / ETG.1000 / CiA 402 values. Nothing here decides
whether the drive is right.
"""

import json
import struct
import sys
import time

import pysoem

IFACE, MODE, CYCLES, CYCLE_NS = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
DC = MODE == "dc"
CYCLE_S = CYCLE_NS * 1e-9
out = {"mode": MODE}


def abort_of(fn):
    """The SDO abort code of a refused request, None when it was accepted, text otherwise."""
    try:
        fn()
        return None
    except pysoem.SdoError as e:
        return e.abort_code
    except Exception as e:  # noqa: BLE001 - reported to the Rust side as text
        return repr(e)


def u(fmt, data):
    return struct.unpack(fmt, data[: struct.calcsize(fmt)])[0]


m = pysoem.Master()
m.open(IFACE)
out["slaves"] = m.config_init()
s = m.slaves[0]
m.read_state()
out["state_after_init"] = s.state
out["identity"] = {"name": s.name, "vendor": s.man, "product": s.id, "revision": s.rev}
# CoE emergencies as SOEM delivers them (while it reads the mailbox), with the step they came in
emergencies = []
step = ["start"]
s.add_emergency_callback(lambda e: emergencies.append([step[0], e.error_code, e.error_reg]))

# ---- SDO uploads ----
out["device_type"] = u("<I", s.sdo_read(0x1000, 0))
out["device_name"] = s.sdo_read(0x1008, 0).decode(errors="replace")
out["identity_od"] = [u("<I", s.sdo_read(0x1018, k)) for k in (1, 2, 3, 4)]
out["statusword_preop"] = u("<H", s.sdo_read(0x6041, 0))
out["position_preop"] = u("<i", s.sdo_read(0x6064, 0))

# ---- refusals with their abort codes ----
out["aborts"] = {
    "write_6041_read_only": abort_of(lambda: s.sdo_write(0x6041, 0, b"\x00\x00")),
    "write_6060_two_bytes": abort_of(lambda: s.sdo_write(0x6060, 0, b"\x0a\x00")),
    "read_5fff_absent": abort_of(lambda: s.sdo_read(0x5FFF, 0)),
    "read_1018_sub_9": abort_of(lambda: s.sdo_read(0x1018, 9)),
    "write_1c12_00_two": abort_of(lambda: s.sdo_write(0x1C12, 0, b"\x02")),
}
out["mode_after_refused_write"] = u("<b", s.sdo_read(0x6060, 0))
out["assign_after_refused_write"] = u("<B", s.sdo_read(0x1C12, 0))

# ---- free PDO mapping: RxPDO without 0x6060 (the mode by SDO), a TxPDO of four ----
s.sdo_write(0x1C12, 0, b"\x00")
s.sdo_write(0x1600, 0, b"\x00")
out["aborts"]["map_1000_into_1600"] = abort_of(lambda: s.sdo_write(0x1600, 1, struct.pack("<I", 0x10000020)))
RX = [0x60400010, 0x60710010]
TX = [0x60410010, 0x60640020, 0x60610008, 0x603F0010]
# complete access: sub-index 0 as UNSIGNED8 padded to 16 bits, then the entries
out["write_1600_ca"] = abort_of(lambda: s.sdo_write(0x1600, 0, struct.pack("<BxII", 2, *RX), ca=True))
out["read_1600_ca"] = s.sdo_read(0x1600, 0, ca=True).hex()
s.sdo_write(0x1C12, 0, b"\x01")
s.sdo_write(0x1C13, 0, b"\x00")
s.sdo_write(0x1A00, 0, b"\x00")
for k, e in enumerate(TX):
    s.sdo_write(0x1A00, k + 1, struct.pack("<I", e))
s.sdo_write(0x1A00, 0, bytes([len(TX)]))
s.sdo_write(0x1C13, 0, b"\x01")
out["read_1c13_ca"] = s.sdo_read(0x1C13, 0, ca=True).hex()
s.sdo_write(0x6060, 0, b"\x0a")
out["mode_by_sdo"] = u("<b", s.sdo_read(0x6060, 0))

# ---- SDO information: the object list and the descriptions ----
try:
    od = s.od
    out["sdo_info"] = [
        {
            "index": o.index,
            "name": o.name.decode(errors="replace") if isinstance(o.name, bytes) else o.name,
            "object_code": o.object_code,
            "data_type": o.data_type,
            "bit_length": o.bit_length,
            "access": o.obj_access,
            "entries": [
                {
                    "name": e.name.decode(errors="replace") if isinstance(e.name, bytes) else e.name,
                    "data_type": e.data_type,
                    "bit_length": e.bit_length,
                    "access": e.obj_access,
                }
                for e in o.entries
            ],
        }
        for o in od
    ]
except Exception as e:  # noqa: BLE001
    out["sdo_info"] = repr(e)

# ---- an invalid state change: PRE-OP -> OP ----
s.state = pysoem.OP_STATE
s.write_state()
time.sleep(0.05)
m.read_state()
out["preop_to_op"] = {"state": s.state, "al_status": s.al_status}
s.state = pysoem.PREOP_STATE | pysoem.STATE_ACK
s.write_state()
s.state_check(pysoem.PREOP_STATE, 500_000)

# ---- process data, synchronisation ----
if DC:
    # DC-synchronous (ETG.1020 sync mode 2), set in PRE-OP like the rest of the configuration;
    # SOEM's config_map requests SAFE-OP at its end, so SYNC0 goes in through config_func (called
    # in PRE-OP), as SOEM users of servo drives do. First a SYNC0 cycle the drive does not run at:
    # refused with its AL code.
    s.sdo_write(0x1C32, 1, struct.pack("<H", 2))
    s.sdo_write(0x1C33, 1, struct.pack("<H", 2))
    out["dc_found"] = m.config_dc()
    s.config_func = lambda _pos: s.dc_sync(True, 2 * CYCLE_NS)
out["io_size"] = m.config_map()
if DC:
    s.state_check(pysoem.SAFEOP_STATE, 300_000)
    m.read_state()
    out["wrong_sync0"] = {"state": s.state, "al_status": s.al_status}
    s.state = pysoem.PREOP_STATE | pysoem.STATE_ACK
    s.write_state()
    s.state_check(pysoem.PREOP_STATE, 500_000)
    s.dc_sync(True, CYCLE_NS, CYCLE_NS // 2)
s.state = pysoem.SAFEOP_STATE
s.write_state()
out["safeop"] = s.state_check(pysoem.SAFEOP_STATE, 1_000_000)
m.read_state()
out["safeop_al_status"] = s.al_status

RXF, TXF = "<Hh", "<HibH"


def exchange(cw, torque):
    s.output = struct.pack(RXF, cw, torque)
    m.send_processdata()
    wkc = m.receive_processdata(2000)
    sw, pos, mode, err = struct.unpack(TXF, bytes(s.input)[: struct.calcsize(TXF)])
    return wkc, sw, pos, mode, err


def next_cw(sw, prev):
    """CiA 402: the controlword one step towards "operation enabled"."""
    if sw & 0x004F == 0x0008:  # fault
        return 0x0000 if prev & 0x80 else 0x0080
    if sw & 0x004F == 0x0040:  # switch on disabled
        return 0x0006
    if sw & 0x006F == 0x0021:  # ready to switch on
        return 0x0007
    return 0x000F


for _ in range(20):
    exchange(0, 0)
m.state = pysoem.OP_STATE
m.write_state()
exchange(0, 0)
out["op"] = m.state_check(pysoem.OP_STATE, 1_000_000)
out["expected_wkc"] = m.expected_wkc

# ---- cyclic synchronous torque ----
step[0] = "cyclic"
good = bad = 0
cw = 0
enabled_at = None
first_pos = None
excursion = 0
late = 0
jitter_max = 0.0
t_next = time.monotonic()
for k in range(CYCLES):
    torque = 0
    if enabled_at is not None:
        # +-20 % of the rated torque (above the friction), alternating every 100 ms: the motor
        # turns back and forth by a few millimetres of cart travel
        torque = 200 if ((k - enabled_at) // 100) % 2 == 0 else -200
    wkc, sw, pos, mode, err = exchange(cw, torque)
    if wkc == m.expected_wkc:
        good += 1
    else:
        bad += 1
    if enabled_at is None and sw & 0x006F == 0x0027 and mode == 10:
        enabled_at = k
        first_pos = pos
    if first_pos is not None:
        excursion = max(excursion, abs(pos - first_pos))
    cw = next_cw(sw, cw)
    t_next += CYCLE_S
    now = time.monotonic()
    if now > t_next:
        late += 1
        jitter_max = max(jitter_max, now - t_next)
        t_next = now
    else:
        while time.monotonic() < t_next:
            pass
out["cyclic"] = {
    "cycles": CYCLES,
    "wkc_good": good,
    "wkc_bad": bad,
    "enabled_at": enabled_at,
    "statusword_end": sw,
    "mode_display_end": mode,
    "error_code_end": err,
    "position_excursion": excursion,
    "host_late_cycles": late,
    "host_late_max_s": jitter_max,
}
out["position_sdo_vs_pdo"] = [u("<i", s.sdo_read(0x6064, 0)), exchange(0x000F, 0)[2]]

# ---- the master goes silent: the drive's SM watchdog, its fault and emergency ----
step[0] = "silence"
exchange(0x000F, 30)
time.sleep(0.3)
m.read_state()
out["after_silence"] = {"state": s.state, "al_status": s.al_status}
wkc, sw, pos, mode, err = exchange(0x000F, 0)
out["first_exchange_after_silence"] = {"statusword": sw, "error_code": err}
for _ in range(5):
    try:
        s.mbx_receive()
    except Exception:  # noqa: BLE001
        pass
out["emergencies"] = emergencies

# ---- recovery: acknowledge, OP again, fault reset, enable ----
step[0] = "recovery"
s.state = pysoem.SAFEOP_STATE | pysoem.STATE_ACK
s.write_state()
s.state_check(pysoem.SAFEOP_STATE, 500_000)
exchange(0, 0)
m.state = pysoem.OP_STATE
m.write_state()
exchange(0, 0)
out["op_again"] = m.state_check(pysoem.OP_STATE, 1_000_000)
cw = 0
recovered = None
for k in range(300):
    wkc, sw, pos, mode, err = exchange(cw, 0)
    if recovered is None and sw & 0x006F == 0x0027:
        recovered = k
    cw = next_cw(sw, cw)
    time.sleep(CYCLE_S)
for _ in range(5):  # the mailbox: the "error reset" emergency of the fault reset
    try:
        s.mbx_receive()
    except Exception:  # noqa: BLE001
        pass
    exchange(cw, 0)
out["recovered_after_cycles"] = recovered
out["error_code_after_recovery"] = err

# ---- bring the bus down: drive disabled, OP -> SAFE-OP -> PRE-OP -> INIT, acknowledging ----
for _ in range(5):
    exchange(0, 0)
for st in (pysoem.SAFEOP_STATE, pysoem.PREOP_STATE):
    m.state = st | pysoem.STATE_ACK
    m.write_state()
    m.state_check(st, 500_000)
# ---- an unsupported mailbox protocol (FoE) gets a mailbox error reply, not silence. Last, in
# PRE-OP: SOEM keeps the error in its list, which makes every later SDO access and config_map raise,
# and it waits out the timeout whatever the answer ----
t0 = time.monotonic()
try:
    s.foe_read("firmware.bin", 0, 64, 200_000)
    out["foe"] = "accepted"
except Exception as e:  # noqa: BLE001
    out["foe"] = type(e).__name__ + ": " + str(e)
out["foe_s"] = time.monotonic() - t0

m.state = pysoem.INIT_STATE | pysoem.STATE_ACK
m.write_state()
m.state_check(pysoem.INIT_STATE, 500_000)
m.read_state()
out["final"] = {"state": s.state, "al_status": s.al_status}
m.close()
print(json.dumps(out))
