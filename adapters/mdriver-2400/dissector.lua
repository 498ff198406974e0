-- mdriver-2400: compressor motor driver, 2400 8N1 (specs 002; README "mdriver-2400").
-- Frame: src dst cmd n data[n+1] cs, n = data length - 1, the sum of ALL bytes including cs is
-- 0x55 mod 256.
local drivegate = _G.drivegate
if not drivegate.first_load("mdriver-2400") then return end

local p = Proto("mdriver2400", "Compressor motor driver 2400 (drivegate mdriver-2400)")

local commands = { [0x00] = "Fixed-code check", [0x10] = "Run" }
local change_times = { [0x01] = "Normal ramp (360 rpm/s)", [0xFF] = "Continuous mode" }
local errors = {
  [0x00] = "None", [0x0C] = "No frame from the master for 6 s, motor stopped",
}

local f = drivegate.fields(p, "mdriver2400", {
  { "src", "uint8", "Source", base.HEX },
  { "dst", "uint8", "Destination", base.HEX },
  { "cmd", "uint8", "Command", base.HEX, commands },
  { "n", "uint8", "n (data length - 1)" },
  { "data", "bytes", "Data" },
  { "code", "bytes", "Fixed code", filter = "fixed_code" },
  { "target", "uint8", "Target frequency code", base.HEX, filter = "target_code" },
  { "change", "uint8", "Change time", base.HEX, change_times, filter = "change_time" },
  { "actual", "uint8", "Actual frequency code", base.HEX, filter = "actual_code" },
  { "reserved", "uint8", "Reserved", base.HEX },
  { "error", "uint8", "Error code", base.HEX, errors },
  { "ipm", "uint8", "IPM temperature (deg C)", filter = "ipm_temp" },
  { "info", "uint8", "Info", base.HEX },
  { "cs", "uint8", "Checksum (sum = 0x55)", base.HEX, filter = "checksum" },
  { "cs_status", "checksum_status", "Checksum status", filter = "checksum.status" },
})
local e_bad, e_len = drivegate.experts(p, "mdriver2400.checksum.bad", "Bad checksum",
                                       "mdriver2400.length", "Length byte does not match the frame")

function p.dissector(tvb, pinfo, tree)
  local t, len = drivegate.frame_tree(p, "MDRIVER-2400", tvb, pinfo, tree, 6, f.data, e_len)
  if not t then return len end
  local to_drive = pinfo.p2p_dir == 0
  t:add(f.src, tvb(0, 1))
  t:add(f.dst, tvb(1, 1))
  t:add(f.cmd, tvb(2, 1))
  local cmd = tvb(2, 1):uint()
  local ni = t:add(f.n, tvb(3, 1))
  local dlen = len - 5
  if tvb(3, 1):uint() + 1 ~= dlen then ni:add_proto_expert_info(e_len) end
  local dt = t:add(f.data, tvb(4, dlen))
  local info = (commands[cmd] or string.format("Command 0x%02x", cmd)) .. (to_drive and "" or " reply")
  if cmd == 0x00 then
    dt:add(f.code, tvb(4, dlen))
  elseif cmd == 0x10 and to_drive and dlen >= 2 then
    dt:add(f.target, tvb(4, 1))
    dt:add(f.change, tvb(5, 1))
    if dlen >= 3 then dt:add(f.reserved, tvb(6, 1)) end
    info = info .. string.format(", code 0x%02x", tvb(4, 1):uint())
  elseif cmd == 0x10 and dlen >= 8 then
    dt:add(f.target, tvb(4, 1))
    dt:add(f.actual, tvb(5, 1))
    dt:add(f.reserved, tvb(6, 1))
    dt:add(f.error, tvb(7, 1))
    dt:add(f.ipm, tvb(8, 1))
    for i = 0, 2 do
      dt:add(f.info, tvb(9 + i, 1)):set_text(string.format("Info %d: 0x%02x", i + 1,
                                                           tvb(9 + i, 1):uint()))
    end
    info = info .. string.format(", actual 0x%02x", tvb(5, 1):uint())
    if tvb(7, 1):uint() ~= 0 then info = info .. string.format(", error 0x%02x", tvb(7, 1):uint()) end
  end
  pinfo.cols.info = info
  local sum = 0
  for i = 0, len - 2 do sum = sum + tvb(i, 1):uint() end
  drivegate.add_checksum(t, pinfo, f.cs, f.cs_status, e_bad, tvb(len - 1, 1),
                         (0x55 - sum) % 256)
  return len
end

DissectorTable.get("drivegate.adapter"):add("mdriver-2400", p)
