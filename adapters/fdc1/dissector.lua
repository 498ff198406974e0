-- fdc1: FDC1 12-42 V DC compressor controller, protocol v2 (specs 003; README "fdc1"). Every
-- number in the document is decimal: 27 76 = 1B 4C, 72 80 = 48 50, 72 115 = 48 73, 85 = 55.
--   status (controller, every 0.5 s, 8 bytes): 27 76 b3 b4 b5 b6 co ce; co = b1^b3^b5,
--     ce = b2^b4^b6
--   programming (master, 22 bytes): 72 80 b3..b20 co ce (the same XOR pair over bytes 1..20);
--     echoed by the controller with bytes 1..2 replaced by 27 80
--   speed programming (master, 8 bytes): 72 115 minH minL maxH maxL 85 x, x = b1^..^b7
local drivegate = _G.drivegate
if not drivegate.first_load("fdc1") then return end
local bxor = drivegate.bxor

local p = Proto("fdc1", "FDC1 compressor controller (drivegate fdc1)")

local kinds = { status = "Status", program = "Programming", echo = "Programming echo",
                speed = "Speed programming" }
local alarms = {
  [0x1] = "Battery out of limits", [0x2] = "Fan overload", [0x3] = "Motor failed to start",
  [0x4] = "Motor overload", [0x5] = "Over-temperature", [0xA] = "Battery out of limits, end of retries",
  [0xB] = "Fan overload, end of retries", [0xC] = "Motor failed to start, end of retries",
  [0xD] = "Motor overload, end of retries", [0xF] = "Internal error",
}

local f = drivegate.fields(p, "fdc1", {
  { "header", "bytes", "Header" },
  { "b3", "uint8", "b3 (0: motor off)" },
  { "rpm", "uint16", "Speed (rpm)" },
  { "alarm", "uint8", "Alarm code", base.HEX },
  { "current", "uint16", "Current (A x 3160)" },
  { "restart", "uint16", "Time to next start (s x 122)", filter = "time_to_restart" },
  { "min_rpm", "uint16", "Minimum speed (rpm)" },
  { "max_rpm", "uint16", "Maximum speed (rpm)" },
  { "fixed", "uint8", "Fixed (85)" },
  { "reserved", "uint8", "Reserved" },
  { "mode", "uint8", "Mode" },
  { "level", "uint16", "Level (V x 1187)" },
  { "data", "bytes", "Data" },
  { "checksum_odd", "uint8", "Checksum (odd bytes)", base.HEX },
  { "checksum_even", "uint8", "Checksum (even bytes)", base.HEX },
  { "checksum", "uint8", "Checksum (XOR of bytes 1..7)", base.HEX },
  { "checksum_status", "checksum_status", "Checksum status", filter = "checksum.status" },
})
local e_bad, e_unknown = drivegate.experts(p, "fdc1.checksum.bad", "Bad checksum",
                                           "fdc1.unknown", "Not an FDC1 frame")

-- XOR of the odd-numbered and of the even-numbered (1-based) bytes of tvb[0, n).
local function xor_pair(tvb, n, first0, first1)
  local odd, even = first0 or tvb(0, 1):uint(), first1 or tvb(1, 1):uint()
  for i = 2, n - 1 do
    if i % 2 == 0 then odd = bxor(odd, tvb(i, 1):uint()) else even = bxor(even, tvb(i, 1):uint()) end
  end
  return odd, even
end

local function pair_checksum(t, pinfo, tvb, len, odd, even)
  local ok1 = drivegate.add_checksum(t, pinfo, f.checksum_odd, f.checksum_status, e_bad,
                                     tvb(len - 2, 1), odd)
  local ok2 = drivegate.add_checksum(t, pinfo, f.checksum_even, f.checksum_status, e_bad,
                                     tvb(len - 1, 1), even)
  return ok1 and ok2
end

local function program_fields(t, tvb)
  t:add(f.min_rpm, tvb(2, 2))
  t:add(f.max_rpm, tvb(4, 2))
  t:add(f.reserved, tvb(6, 1))
  t:add(f.mode, tvb(7, 1))
  for i = 0, 5 do t:add(f.level, tvb(8 + 2 * i, 2)) end
end

function p.dissector(tvb, pinfo, tree)
  local len = tvb:len()
  pinfo.cols.protocol = "FDC1"
  local t = tree:add(p, tvb())
  local h0 = len >= 1 and tvb(0, 1):uint() or -1
  local h1 = len >= 2 and tvb(1, 1):uint() or -1
  if len == 8 and h0 == 27 and h1 == 76 then
    t:add(f.header, tvb(0, 2))
    t:add(f.b3, tvb(2, 1))
    if tvb(2, 1):uint() == 0 then
      t:add(f.alarm, tvb(3, 1)):append_text(" (" .. (alarms[math.floor(tvb(3, 1):uint() / 16)] or
                                                      (tvb(3, 1):uint() == 0 and "none" or "?")) .. ")")
      t:add(f.restart, tvb(4, 2))
      pinfo.cols.info = string.format("Status: motor off, alarm 0x%02x", tvb(3, 1):uint())
    else
      t:add(f.rpm, tvb(2, 2))
      t:add(f.current, tvb(4, 2))
      pinfo.cols.info = string.format("Status: motor on, %d rpm", tvb(2, 2):uint())
    end
    pair_checksum(t, pinfo, tvb, len, xor_pair(tvb, 6))
  elseif len == 8 and h0 == 72 and h1 == 115 then
    t:add(f.header, tvb(0, 2))
    t:add(f.min_rpm, tvb(2, 2))
    t:add(f.max_rpm, tvb(4, 2))
    t:add(f.fixed, tvb(6, 1))
    pinfo.cols.info = string.format("Speed programming: %d..%d rpm", tvb(2, 2):uint(),
                                    tvb(4, 2):uint())
    drivegate.add_checksum(t, pinfo, f.checksum, f.checksum_status, e_bad, tvb(7, 1),
                           drivegate.xor(tvb, 0, 7))
  elseif len == 22 and h0 == 72 and h1 == 80 then
    t:add(f.header, tvb(0, 2))
    program_fields(t, tvb)
    pinfo.cols.info = "Programming"
    pair_checksum(t, pinfo, tvb, len, xor_pair(tvb, 20))
  elseif len == 22 and h0 == 27 and h1 == 80 then
    t:add(f.header, tvb(0, 2))
    program_fields(t, tvb)
    pinfo.cols.info = "Programming echo"
    -- The checksums may be those sent (over 72 80) or recomputed over 27 80.
    local o1, e1 = xor_pair(tvb, 20, 72, 80)
    if tvb(20, 1):uint() == o1 and tvb(21, 1):uint() == e1 then
      pair_checksum(t, pinfo, tvb, len, o1, e1)
    else
      pair_checksum(t, pinfo, tvb, len, xor_pair(tvb, 20))
    end
  else
    t:add(f.data, tvb())
    t:add_proto_expert_info(e_unknown)
    pinfo.cols.info = string.format("Unknown frame, %d bytes", len)
  end
  return len
end

DissectorTable.get("drivegate.adapter"):add("fdc1", p)
