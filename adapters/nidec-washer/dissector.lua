-- nidec-washer: Nidec washing-machine inverter, spec V07 (specs 000; README "nidec-washer").
-- Master frame (11 bytes): A5 MODE d1..d8 X; slave frame (7): A5 MODE e1..e4 X, FCT reply (13):
-- A5 66 e1..e10 X; NACK: 5A 00 FF 00 FF 00 5A. X = XOR of every byte before it.
local drivegate = _G.drivegate
if not drivegate.first_load("nidec-washer") then return end

local p = Proto("nidec_washer", "Nidec washer inverter (drivegate nidec-washer)")

local modes = {
  [0x02] = "Ping", [0x05] = "Request", [0x09] = "CW", [0x0B] = "CCW", [0x0C] = "Agitation",
  [0x0D] = "Spin", [0x1B] = "Forced brake", [0x1D] = "Free-shaft spin", [0x27] = "Stop",
  [0x29] = "Brake", [0x2B] = "Voltage detection", [0x2C] = "Weight detection",
  [0x2D] = "Fabric detection", [0x66] = "FCT test",
}
local headers = { [0xA5] = "Frame (A5)", [0x5A] = "NACK (5A)" }

local f = drivegate.fields(p, "nidec_washer", {
  { "header", "uint8", "Header", base.HEX, headers },
  { "mode", "uint8", "Mode", base.HEX, modes },
  { "data", "bytes", "Data" },
  { "d", "uint8", "d", base.HEX },
  { "speed", "uint16", "Speed (rpm)" },
  { "accel", "uint16", "Acceleration time (100 ms)" },
  { "platform", "uint8", "Platform" },
  { "weight_raw", "uint16", "Empty-basket raw weight", filter = "empty_weight_raw" },
  { "error", "uint8", "Error", base.HEX },
  { "error_bits", "bits", filter = "error", flags = {
    { "general", "General fault" },
    { "ipm_over_temp", "IPM over-temperature" },
    { "dc_over_voltage", "DC bus over-voltage" },
    { "stall", "Stall / tacho missing" },
    { "over_current", "Hardware over-current" },
    { "under_voltage", "Bus under-voltage" },
    { "lost_phase", "Lost phase" },
    { "motor_over_temp", "Motor over-temperature" },
  } },
  { "e", "uint8", "e", base.HEX },
  { "checksum", "uint8", "Checksum (XOR)", base.HEX },
  { "checksum_status", "checksum_status", "Checksum status", filter = "checksum.status" },
})
local e_bad, e_len = drivegate.experts(p, "nidec_washer.checksum.bad", "Bad checksum",
                                       "nidec_washer.length", "Unexpected frame length")

local run_modes = { [0x09] = true, [0x0B] = true, [0x0D] = true, [0x1D] = true }

function p.dissector(tvb, pinfo, tree)
  local t, len = drivegate.frame_tree(p, "NIDEC-WASHER", tvb, pinfo, tree, 3, f.data, e_len)
  if not t then return len end
  local header = tvb(0, 1):uint()
  local mode = tvb(1, 1):uint()
  local to_drive = pinfo.p2p_dir == 0
  t:add(f.header, tvb(0, 1))
  local n = len - 3  -- data bytes
  if header == 0x5A then
    pinfo.cols.info = "NACK"
    t:add(f.data, tvb(1, n + 0))
  else
    t:add(f.mode, tvb(1, 1))
    local name = modes[mode] or string.format("Mode 0x%02x", mode)
    pinfo.cols.info = (to_drive and "" or "Reply ") .. name
    if n > 0 then
      local dt = t:add(f.data, tvb(2, n))
      if to_drive then
        if n ~= 8 then t:add_proto_expert_info(e_len) end
        for i = 0, n - 1 do
          dt:add(f.d, tvb(2 + i, 1)):set_text(string.format("d%d: 0x%02x", i + 1, tvb(2 + i, 1):uint()))
        end
        if run_modes[mode] and n >= 4 then
          t:add(f.speed, tvb(2, 2))
          t:add(f.accel, tvb(4, 2))
          pinfo.cols.info:append(string.format(", %d rpm", tvb(2, 2):uint()))
        elseif mode == 0x02 and n >= 3 then
          t:add(f.platform, tvb(2, 1))
          t:add(f.weight_raw, tvb(3, 2))
        end
      else
        if n ~= 4 and not (mode == 0x66 and n == 10) then t:add_proto_expert_info(e_len) end
        drivegate.add_bits(dt:add(f.error, tvb(2, 1)), f.error_bits, tvb(2, 1))
        for i = 1, n - 1 do
          dt:add(f.e, tvb(2 + i, 1)):set_text(string.format("e%d: 0x%02x", i + 1, tvb(2 + i, 1):uint()))
        end
        if tvb(2, 1):uint() ~= 0 then
          pinfo.cols.info:append(string.format(", error 0x%02x", tvb(2, 1):uint()))
        end
      end
    end
  end
  drivegate.add_checksum(t, pinfo, f.checksum, f.checksum_status, e_bad, tvb(len - 1, 1),
                         drivegate.xor(tvb, 0, len - 1))
  return len
end

DissectorTable.get("drivegate.adapter"):add("nidec-washer", p)
