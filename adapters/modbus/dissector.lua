-- modbus: a Modbus serial-line slave read and written through a profile (README "modbus").
-- RTU (MODBUS over Serial Line V1.02, 2.5.1): address, PDU (function, data: MODBUS Application
-- Protocol V1.1b3, 6.x), CRC-16 (init FFFF, poly A001, low byte first, Serial Line 6.2.2).
-- ASCII (2.5.2): ':' then address, PDU and LRC as hex characters, CR LF; decoded, then shown as
-- RTU is. Wireshark's own "modbus" / "mbrtu" names are taken: this protocol is drivegate_modbus.
local drivegate = _G.drivegate
if not drivegate.first_load("modbus") then return end
local band = drivegate.band

local p = Proto("drivegate_modbus", "Modbus serial line (drivegate modbus)")

-- Application Protocol 6.x.
local functions = {
  [0x01] = "Read coils", [0x02] = "Read discrete inputs", [0x03] = "Read holding registers",
  [0x04] = "Read input registers", [0x05] = "Write single coil",
  [0x06] = "Write single register", [0x07] = "Read exception status", [0x08] = "Diagnostics",
  [0x0B] = "Get comm event counter", [0x0C] = "Get comm event log",
  [0x0F] = "Write multiple coils", [0x10] = "Write multiple registers",
  [0x11] = "Report server id", [0x14] = "Read file record", [0x15] = "Write file record",
  [0x16] = "Mask write register", [0x17] = "Read/write registers", [0x18] = "Read FIFO queue",
  [0x2B] = "Encapsulated interface",
}
-- Application Protocol 7.
local exceptions = {
  [0x01] = "Illegal function", [0x02] = "Illegal data address", [0x03] = "Illegal data value",
  [0x04] = "Server device failure", [0x05] = "Acknowledge", [0x06] = "Server device busy",
  [0x08] = "Memory parity error", [0x0A] = "Gateway path unavailable",
  [0x0B] = "Gateway target device failed to respond",
}
local mei_types = { [0x0D] = "CANopen general reference", [0x0E] = "Read device identification" }

local f = drivegate.fields(p, "drivegate_modbus", {
  { "framing", "string", "Framing" },
  drivegate.modbus_rtu_rows(functions),
  { "exception_code", "uint8", "Exception code", base.DEC, exceptions },
  { "register", "uint16", "Start address" },
  { "count", "uint16", "Quantity" },
  { "write_register", "uint16", "Write start address" },
  { "write_count", "uint16", "Write quantity" },
  { "byte_count", "uint8", "Byte count" },
  { "value", "uint16", "Value", base.HEX },
  { "and_mask", "uint16", "AND mask", base.HEX },
  { "or_mask", "uint16", "OR mask", base.HEX },
  { "word", "uint16", "Register", base.HEX },
  { "bits", "bytes", "Bits" },
  { "mei", "uint8", "MEI type", base.HEX, mei_types },
  { "data", "bytes", "Data" },
  { "crc", "uint16", "CRC-16", base.HEX },
  { "lrc", "uint8", "LRC", base.HEX },
  { "crc_status", "checksum_status", "Checksum status", filter = "crc.status" },
})
local e_bad, e_len = drivegate.experts(p, "drivegate_modbus.crc.bad", "Bad checksum",
                                       "drivegate_modbus.length", "Unexpected frame length")

-- LRC of Serial Line 6.2.1: the two's complement of the 8-bit sum of tvb[0, len).
local function lrc(tvb, len)
  local sum = 0
  for i = 0, len - 1 do sum = sum + tvb(i, 1):uint() end
  return band(-sum, 0xFF)
end

local function words(t, tvb, from, to)
  drivegate.words(t, tvb, from, to, f.word, f.data)
end

-- The PDU in tvb[1, body): its fields; the Info column's text.
local function pdu(t, tvb, body, to_drive)
  local fn = tvb(1, 1):uint()
  local ft = t:add(f.func, tvb(1, 1))
  ft:add(f.exception_flag, tvb(1, 1))
  local info = functions[band(fn, 0x7F)] or string.format("Function 0x%02x", band(fn, 0x7F))
  local n = body - 2  -- data bytes after the function code
  local function need(k)
    if n ~= k then t:add_proto_expert_info(e_len) end
    return n >= k
  end
  if band(fn, 0x80) ~= 0 then
    info = info .. " exception"
    if need(1) then
      t:add(f.exception_code, tvb(2, 1))
      info = info .. string.format(" %d", tvb(2, 1):uint())
    end
  elseif fn >= 0x01 and fn <= 0x04 then
    if to_drive then
      if need(4) then
        info = info .. drivegate.start_quantity(t, tvb, f.register, f.count, " %d x%d")
      end
    elseif n >= 1 then
      t:add(f.byte_count, tvb(2, 1))
      if tvb(2, 1):uint() ~= n - 1 then t:add_proto_expert_info(e_len) end
      if n > 1 then
        if fn <= 0x02 then t:add(f.bits, tvb(3, n - 1)) else words(t, tvb, 3, body) end
      end
      info = info .. " reply"
    else
      t:add_proto_expert_info(e_len)
    end
  elseif fn == 0x05 or fn == 0x06 then
    if need(4) then
      t:add(f.register, tvb(2, 2))
      t:add(f.value, tvb(4, 2))
      info = info .. string.format(" %d = 0x%04x", tvb(2, 2):uint(), tvb(4, 2):uint())
    end
  elseif fn == 0x0F or fn == 0x10 then
    if n >= 4 then
      info = info .. drivegate.start_quantity(t, tvb, f.register, f.count, " %d x%d")
      if to_drive and n >= 5 then
        t:add(f.byte_count, tvb(6, 1))
        if tvb(6, 1):uint() ~= n - 5 then t:add_proto_expert_info(e_len) end
        if n > 5 then
          if fn == 0x0F then t:add(f.bits, tvb(7, n - 5)) else words(t, tvb, 7, body) end
        end
      elseif not to_drive and n ~= 4 then
        t:add_proto_expert_info(e_len)
      end
    else
      t:add_proto_expert_info(e_len)
    end
  elseif fn == 0x16 then
    if need(6) then
      t:add(f.register, tvb(2, 2))
      t:add(f.and_mask, tvb(4, 2))
      t:add(f.or_mask, tvb(6, 2))
    end
  elseif fn == 0x17 then
    if to_drive then
      if n >= 9 then
        t:add(f.register, tvb(2, 2))
        t:add(f.count, tvb(4, 2))
        t:add(f.write_register, tvb(6, 2))
        t:add(f.write_count, tvb(8, 2))
        t:add(f.byte_count, tvb(10, 1))
        words(t, tvb, 11, body)
      else
        t:add_proto_expert_info(e_len)
      end
    elseif n >= 1 then
      t:add(f.byte_count, tvb(2, 1))
      words(t, tvb, 3, body)
    end
  elseif fn == 0x2B then
    if n >= 1 then
      t:add(f.mei, tvb(2, 1))
      if n > 1 then t:add(f.data, tvb(3, n - 1)) end
    end
  elseif n > 0 then
    t:add(f.data, tvb(2, n))
  end
  return info
end

function p.dissector(tvb, pinfo, tree)
  local len = tvb:len()
  pinfo.cols.protocol = "MODBUS"
  local t = tree:add(p, tvb())
  local to_drive = pinfo.p2p_dir == 0
  if len >= 1 and tvb(0, 1):uint() == 0x3A then  -- ':' : ASCII framing
    t:add(f.framing, tvb(0, 1), "ASCII")
    local text = tvb(0, len):string()
    local hex = text:match("^:(%x+)\r\n$")
    if hex == nil or #hex % 2 ~= 0 or #hex < 6 then
      t:add(f.data, tvb())
      t:add_proto_expert_info(e_len)
      pinfo.cols.info = "ASCII frame"
      return len
    end
    local bytes = ByteArray.new(hex)
    local frame = bytes:tvb("Modbus ASCII frame")
    local flen = frame:len()
    t:add(f.address, frame(0, 1))
    local info = pdu(t, frame, flen - 1, to_drive)
    pinfo.cols.info = (frame(0, 1):uint() == 0 and "Broadcast " or "") .. info
    drivegate.add_checksum(t, pinfo, f.lrc, f.crc_status, e_bad, frame(flen - 1, 1),
                           lrc(frame, flen - 1))
    return len
  end
  if len < 4 then
    t:add(f.data, tvb())
    t:add_proto_expert_info(e_len)
    return len
  end
  t:add(f.framing, tvb(0, 0), "RTU"):set_generated()
  t:add(f.address, tvb(0, 1))
  local info = pdu(t, tvb, len - 2, to_drive)
  pinfo.cols.info = (tvb(0, 1):uint() == 0 and "Broadcast " or "") .. info
  drivegate.add_crc16_modbus(t, pinfo, f.crc, f.crc_status, e_bad, tvb, len)
  return len
end

DissectorTable.get("drivegate.adapter"):add("modbus", p)
