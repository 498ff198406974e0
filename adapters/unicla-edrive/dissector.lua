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

local f = drivegate.fields(p, "unicla_edrive", {
  { "sof", "uint8", "Start of frame", base.HEX },
  { "eof", "uint8", "End of frame", base.HEX },
  { "header", "bytes", "Header" },
  { "source", "uint8", "Source", base.HEX },
  { "destination", "uint8", "Destination", base.HEX },
  { "command", "uint8", "Command", base.HEX, commands },
  { "message_id", "uint8", "Message id", base.HEX, messages },
  { "sequence", "uint8", "Sequence" },
  { "zero", "uint16", "Reserved (0)", base.HEX, filter = "reserved" },
  { "size", "uint8", "Payload size", filter = "payload_size" },
  { "payload", "bytes", "Payload" },
  { "speed", "uint16", "Speed (rpm, 0 = stop)" },
  -- The status payload (message 01, 64 bytes: the document's "Status" table, eight bytes a row).
  { "status", "layout", fields = {
    { "suction_pressure", "float", "Suction pressure (bar-a)", at = 0 },
    { "discharge_pressure", "float", "Discharge pressure (bar-a)", at = 4 },
    { "suction_temperature", "float", "Suction temperature (degC)", at = 8 },
    { "discharge_temperature", "float", "Discharge temperature (degC)", at = 12 },
    { "suction_superheat", "float", "Suction superheat (K)", at = 16 },
    { "discharge_superheat", "float", "Discharge superheat (K)", at = 20 },
    { "rpm", "uint16", "Speed (rpm)", at = 24 },
    { "volts", "uint16", "Voltage (V)", at = 26 },
    { "watts", "uint16", "Power (W)", at = 28 },
    { "torque", "uint16", "Torque (Nm)", at = 30 },
    { "op_state", "uint8", "Operating state", at = 32 },
    { "control_mode", "uint8", "Control mode", at = 33 },
    { "demand", "uint8", "Demand (%)", at = 34 },
    { "remote_enable", "uint8", "Remote enable", at = 35 },
    { "anti_short", "uint8", "Anti-short cycle", at = 36 },
    { "motor_temperature", "float", "Motor temperature (degC)", at = 40 },
    { "switch_temperature", "float", "Switch temperature (degC)", at = 44 },
    { "compressor_run", "uint16", "Compressor run safety flags", base.HEX,
      filter = "compressor_run_flags", at = 48 },
    { "compressor_start", "uint16", "Compressor start safety flags", base.HEX,
      filter = "compressor_start_flags", at = 50 },
    { "motor_run", "uint16", "Motor run safety flags", base.HEX, filter = "motor_run_flags",
      at = 52 },
    { "motor_start", "uint16", "Motor start safety flags", base.HEX,
      filter = "motor_start_flags", at = 54 },
    { "electrical", "uint24", "Electrical safety flags", base.HEX, filter = "electrical_flags",
      at = 56 },
  } },
  { "crc", "uint16", "CRC-16/XMODEM", base.HEX },
  { "crc_status", "checksum_status", "CRC status", filter = "crc.status" },
})
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
  -- Unstuff what lies between the flags (7D 5E: 7E, 7D 5D: 7D) into a tvb of its own.
  local raw = drivegate.unstuff(tvb, 0x7D, 0x20)
  t:add(f.eof, tvb(len - 1, 1))
  if not raw or raw:len() < 10 then
    t:add_proto_expert_info(e_frame)
    pinfo.cols.info = "Short frame"
    return len
  end
  local n = raw:len()
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
      drivegate.add_layout(pt, u, 8, f.status)
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
