-- ed3100: ED3100 variable-frequency drive, Modbus RTU with quirks (specs 001; README "ed3100").
-- address, function, fields, CRC-16 (init FFFF, poly A001, low byte first). Its 03 reply echoes
-- the 2-byte register address instead of a byte count; the standard form is accepted too.
local drivegate = _G.drivegate
if not drivegate.first_load("ed3100") then return end
local band = drivegate.band

local p = Proto("ed3100", "ED3100 drive Modbus RTU (drivegate ed3100)")

local functions = { [0x03] = "Read registers", [0x06] = "Write register",
                    [0x10] = "Write registers" }
local registers = { [0x2000] = "Drive command", [0x2001] = "Frequency (0.01 Hz)",
                    [0x0E01] = "Fault / state" }
local commands = { [0x001E] = "Forward continuous", [0x0012] = "Forward one-shot",
                   [0x002E] = "Reverse continuous", [0x0001] = "Stop" }

local f = drivegate.fields(p, "ed3100", {
  drivegate.modbus_rtu_rows(functions),
  { "register", "uint16", "Register", base.HEX, registers },
  { "count", "uint16", "Register count" },
  { "byte_count", "uint8", "Byte count" },
  { "value", "uint16", "Value", base.HEX },
  { "command", "uint16", "Drive command", base.HEX, commands },
  { "word", "uint16", "Data word", base.HEX },
  { "exception_code", "uint8", "Exception code" },
  { "data", "bytes", "Data" },
  { "crc", "uint16", "CRC-16", base.HEX },
  { "crc_status", "checksum_status", "CRC status", filter = "crc.status" },
})
local e_bad, e_len = drivegate.experts(p, "ed3100.crc.bad", "Bad CRC",
                                       "ed3100.length", "Unexpected frame length")

local function words(t, tvb, from, to)
  drivegate.words(t, tvb, from, to, f.word, f.data)
end

function p.dissector(tvb, pinfo, tree)
  local t, len = drivegate.frame_tree(p, "ED3100", tvb, pinfo, tree, 4, f.data, e_len)
  if not t then return len end
  local to_drive = pinfo.p2p_dir == 0
  t:add(f.address, tvb(0, 1))
  local ft = t:add(f.func, tvb(1, 1))
  ft:add(f.exception_flag, tvb(1, 1))
  local fn = tvb(1, 1):uint()
  local body = len - 2  -- end of the fields, before the CRC
  local info = (functions[band(fn, 0x7F)] or string.format("Function 0x%02x", fn))
  if band(fn, 0x80) ~= 0 then
    info = info .. " exception"
    if body >= 3 then t:add(f.exception_code, tvb(2, 1)) end
  elseif fn == 0x03 then
    if to_drive then
      if body == 6 then
        info = info .. drivegate.start_quantity(t, tvb, f.register, f.count, " 0x%04x x%d")
      else
        t:add_proto_expert_info(e_len)
      end
    elseif body >= 3 and tvb(2, 1):uint() == body - 3 then  -- standard: byte count, data
      t:add(f.byte_count, tvb(2, 1))
      words(t, tvb, 3, body)
      info = info .. " reply (standard form)"
    elseif body >= 4 then  -- ED3100 form: the register address, then the words
      t:add(f.register, tvb(2, 2))
      words(t, tvb, 4, body)
      info = info .. string.format(" reply 0x%04x", tvb(2, 2):uint())
    else
      t:add_proto_expert_info(e_len)
    end
  elseif fn == 0x06 then
    if body == 6 then
      local reg = tvb(2, 2):uint()
      t:add(f.register, tvb(2, 2))
      if reg == 0x2000 then t:add(f.command, tvb(4, 2)) else t:add(f.value, tvb(4, 2)) end
      info = info .. string.format(" 0x%04x = 0x%04x", reg, tvb(4, 2):uint())
    else
      t:add_proto_expert_info(e_len)
    end
  elseif fn == 0x10 then
    if body >= 6 then
      info = info .. drivegate.start_quantity(t, tvb, f.register, f.count, " 0x%04x x%d")
      if to_drive and body >= 7 then
        t:add(f.byte_count, tvb(6, 1))
        words(t, tvb, 7, body)
      end
    else
      t:add_proto_expert_info(e_len)
    end
  elseif body > 2 then
    t:add(f.data, tvb(2, body - 2))
  end
  pinfo.cols.info = (tvb(0, 1):uint() == 0 and "Broadcast " or "") .. info
  drivegate.add_crc16_modbus(t, pinfo, f.crc, f.crc_status, e_bad, tvb, len)
  return len
end

DissectorTable.get("drivegate.adapter"):add("ed3100", p)
