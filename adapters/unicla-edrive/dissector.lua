-- unicla-edrive: Unicla eDrive compressor, RS-485 interface V16 (specs 004; README
-- "unicla-edrive"). Frame: 7E | header(8) payload CRC(2) | 7E, stuffed between the flags
-- (7E -> 7D 5E, 7D -> 7D 5D). Header: source, destination, command (C0 read, C1 write), message
-- id, sequence, 0, 0, payload size. CRC-16/XMODEM (poly 1021, init 0) over header + payload,
-- before stuffing, high byte first. Values big-endian (the adapter's default).
local drivegate = _G.drivegate
if not drivegate.first_load("unicla-edrive") then return end
local bxor, band, lshift = drivegate.bxor, drivegate.band, drivegate.lshift

local p = Proto("unicla_edrive", "Unicla eDrive compressor (drivegate unicla-edrive)")

local commands = { [0xC0] = "Read", [0xC1] = "Write" }
local messages = { [0x01] = "Status", [0x02] = "Build information", [0x03] = "Running limits",
                   [0xC0] = "Set run state", [0xC1] = "Acknowledge faults" }

local f = {
  sof      = ProtoField.uint8("unicla_edrive.sof", "Start of frame", base.HEX),
  eof      = ProtoField.uint8("unicla_edrive.eof", "End of frame", base.HEX),
  header   = ProtoField.bytes("unicla_edrive.header", "Header"),
  source   = ProtoField.uint8("unicla_edrive.source", "Source", base.HEX),
  destination = ProtoField.uint8("unicla_edrive.destination", "Destination", base.HEX),
  command  = ProtoField.uint8("unicla_edrive.command", "Command", base.HEX, commands),
  message_id = ProtoField.uint8("unicla_edrive.message_id", "Message id", base.HEX, messages),
  sequence = ProtoField.uint8("unicla_edrive.sequence", "Sequence", base.DEC),
  zero     = ProtoField.uint16("unicla_edrive.reserved", "Reserved (0)", base.HEX),
  size     = ProtoField.uint8("unicla_edrive.payload_size", "Payload size", base.DEC),
  payload  = ProtoField.bytes("unicla_edrive.payload", "Payload"),
  speed    = ProtoField.uint16("unicla_edrive.speed", "Speed (rpm, 0 = stop)", base.DEC),
  suction_pressure = ProtoField.float("unicla_edrive.suction_pressure", "Suction pressure (bar-a)"),
  discharge_pressure = ProtoField.float("unicla_edrive.discharge_pressure", "Discharge pressure (bar-a)"),
  suction_temperature = ProtoField.float("unicla_edrive.suction_temperature", "Suction temperature (degC)"),
  discharge_temperature = ProtoField.float("unicla_edrive.discharge_temperature", "Discharge temperature (degC)"),
  suction_superheat = ProtoField.float("unicla_edrive.suction_superheat", "Suction superheat (K)"),
  discharge_superheat = ProtoField.float("unicla_edrive.discharge_superheat", "Discharge superheat (K)"),
  rpm      = ProtoField.uint16("unicla_edrive.rpm", "Speed (rpm)", base.DEC),
  volts    = ProtoField.uint16("unicla_edrive.volts", "Voltage (V)", base.DEC),
  watts    = ProtoField.uint16("unicla_edrive.watts", "Power (W)", base.DEC),
  torque   = ProtoField.uint16("unicla_edrive.torque", "Torque (Nm)", base.DEC),
  op_state = ProtoField.uint8("unicla_edrive.op_state", "Operating state", base.DEC),
  control_mode = ProtoField.uint8("unicla_edrive.control_mode", "Control mode", base.DEC),
  demand   = ProtoField.uint8("unicla_edrive.demand", "Demand (%)", base.DEC),
  remote_enable = ProtoField.uint8("unicla_edrive.remote_enable", "Remote enable", base.DEC),
  anti_short = ProtoField.uint8("unicla_edrive.anti_short", "Anti-short cycle", base.DEC),
  motor_temperature = ProtoField.float("unicla_edrive.motor_temperature", "Motor temperature (degC)"),
  switch_temperature = ProtoField.float("unicla_edrive.switch_temperature", "Switch temperature (degC)"),
  compressor_run = ProtoField.uint16("unicla_edrive.compressor_run_flags", "Compressor run safety flags", base.HEX),
  compressor_start = ProtoField.uint16("unicla_edrive.compressor_start_flags", "Compressor start safety flags", base.HEX),
  motor_run = ProtoField.uint16("unicla_edrive.motor_run_flags", "Motor run safety flags", base.HEX),
  motor_start = ProtoField.uint16("unicla_edrive.motor_start_flags", "Motor start safety flags", base.HEX),
  electrical = ProtoField.uint24("unicla_edrive.electrical_flags", "Electrical safety flags", base.HEX),
  crc      = ProtoField.uint16("unicla_edrive.crc", "CRC-16/XMODEM", base.HEX),
  crc_status = ProtoField.uint8("unicla_edrive.crc.status", "CRC status", base.DEC,
                                drivegate.checksum_status),
}
local list = {}
for _, v in pairs(f) do list[#list + 1] = v end
p.fields = list
local e_bad, e_frame = drivegate.experts(p, "unicla_edrive.crc.bad", "Bad CRC",
                                         "unicla_edrive.framing", "Bad framing or length")

local function crc_xmodem(tvb, len)
  local crc = 0
  for i = 0, len - 1 do
    crc = bxor(crc, lshift(tvb(i, 1):uint(), 8))
    for _ = 1, 8 do
      if band(crc, 0x8000) ~= 0 then crc = band(bxor(lshift(crc, 1), 0x1021), 0xFFFF)
      else crc = band(lshift(crc, 1), 0xFFFF) end
    end
  end
  return crc
end

local function status_fields(t, tvb, at)
  t:add(f.suction_pressure, tvb(at, 4))
  t:add(f.discharge_pressure, tvb(at + 4, 4))
  t:add(f.suction_temperature, tvb(at + 8, 4))
  t:add(f.discharge_temperature, tvb(at + 12, 4))
  t:add(f.suction_superheat, tvb(at + 16, 4))
  t:add(f.discharge_superheat, tvb(at + 20, 4))
  t:add(f.rpm, tvb(at + 24, 2))
  t:add(f.volts, tvb(at + 26, 2))
  t:add(f.watts, tvb(at + 28, 2))
  t:add(f.torque, tvb(at + 30, 2))
  t:add(f.op_state, tvb(at + 32, 1))
  t:add(f.control_mode, tvb(at + 33, 1))
  t:add(f.demand, tvb(at + 34, 1))
  t:add(f.remote_enable, tvb(at + 35, 1))
  t:add(f.anti_short, tvb(at + 36, 1))
  t:add(f.motor_temperature, tvb(at + 40, 4))
  t:add(f.switch_temperature, tvb(at + 44, 4))
  t:add(f.compressor_run, tvb(at + 48, 2))
  t:add(f.compressor_start, tvb(at + 50, 2))
  t:add(f.motor_run, tvb(at + 52, 2))
  t:add(f.motor_start, tvb(at + 54, 2))
  t:add(f.electrical, tvb(at + 56, 3))
end

function p.dissector(tvb, pinfo, tree)
  local len = tvb:len()
  pinfo.cols.protocol = "UNICLA-EDRIVE"
  local t = tree:add(p, tvb())
  if len < 2 or tvb(0, 1):uint() ~= 0x7E or tvb(len - 1, 1):uint() ~= 0x7E then
    t:add(f.payload, tvb())
    t:add_proto_expert_info(e_frame)
    pinfo.cols.info = "Unframed bytes"
    return len
  end
  t:add(f.sof, tvb(0, 1))
  -- Unstuff what lies between the flags into a tvb of its own.
  local raw = ByteArray.new()
  local i = 1
  local broken = false
  while i < len - 1 do
    local b = tvb(i, 1):uint()
    if b == 0x7D then
      if i + 1 >= len - 1 then broken = true break end
      b = bxor(tvb(i + 1, 1):uint(), 0x20)
      i = i + 2
    else
      i = i + 1
    end
    raw:append(ByteArray.new(string.format("%02x", b)))
  end
  t:add(f.eof, tvb(len - 1, 1))
  local n = raw:len()
  if broken or n < 10 then
    t:add_proto_expert_info(e_frame)
    pinfo.cols.info = "Short frame"
    return len
  end
  local u = raw:tvb("Unstuffed frame")
  local ht = t:add(f.header, u(0, 8))
  ht:add(f.source, u(0, 1))
  ht:add(f.destination, u(1, 1))
  ht:add(f.command, u(2, 1))
  ht:add(f.message_id, u(3, 1))
  ht:add(f.sequence, u(4, 1))
  ht:add(f.zero, u(5, 2))
  local si = ht:add(f.size, u(7, 1))
  local size = u(7, 1):uint()
  local plen = n - 10
  if size ~= plen then si:add_proto_expert_info(e_frame) end
  local cmd, msg = u(2, 1):uint(), u(3, 1):uint()
  local info = (commands[cmd] or string.format("Command 0x%02x", cmd)) .. " " ..
               (messages[msg] or string.format("message 0x%02x", msg))
  if plen > 0 then
    local pt = t:add(f.payload, u(8, plen))
    if msg == 0x01 and plen == 64 then
      status_fields(pt, u, 8)
      info = info .. string.format(", %d rpm", u(32, 2):uint())
    elseif msg == 0xC0 and plen == 2 then
      pt:add(f.speed, u(8, 2))
      info = info .. string.format(", %d rpm", u(8, 2):uint())
    end
  end
  pinfo.cols.info = info .. string.format(", seq %d", u(4, 1):uint()) ..
                    (pinfo.p2p_dir == 0 and "" or " (reply)")
  drivegate.add_checksum(t, pinfo, f.crc, f.crc_status, e_bad, u(n - 2, 2), crc_xmodem(u, n - 2))
  return len
end

DissectorTable.get("drivegate.adapter"):add("unicla-edrive", p)
