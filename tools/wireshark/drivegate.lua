-- drivegate capture: the LINKTYPE_USER0 (147) pseudo-header of `drivegate capture` pcaps
-- (docs/capture.md), dispatching each frame to its adapter's dissector by adapter id.
--
--   tshark -X lua_script:tools/wireshark/drivegate.lua -r bus.pcap
--
-- This file loads every adapter's dissector (adapters/<id>/dissector.lua, or drivegate_<id>.lua
-- beside it in a plugin folder, the build's or installed); see README.md.

local bxor = (bit32 and bit32.bxor) or bit.bxor
local band = (bit32 and bit32.band) or bit.band
local rshift = (bit32 and bit32.rshift) or bit.rshift
local lshift = (bit32 and bit32.lshift) or bit.lshift

-- Shared by the protocol files: one table in the Lua state's globals (a script's own globals
-- may be private to it, so _G is named). They find it there because this file loads first:
-- it loads them itself, and Wireshark loads a plugin folder's files in name order, drivegate.lua
-- before drivegate_<id>.lua.
local drivegate = _G.drivegate or {}
_G.drivegate = drivegate
drivegate.loaded = drivegate.loaded or {}
drivegate.bxor = bxor
drivegate.band = band
drivegate.bor = (bit32 and bit32.bor) or bit.bor
drivegate.lshift = lshift
drivegate.rshift = rshift

-- True the first time a protocol file `id` asks: each loads once, however it is found (from the
-- source tree, installed beside this file, or by Wireshark from its plugin folder).
function drivegate.first_load(id)
  if drivegate.loaded[id] then return false end
  drivegate.loaded[id] = true
  return true
end

-- The ProtoField constructors of numbers, by the bytes of their value: a row of an integer one is
-- shown in decimal unless it says otherwise; a "layout" row's fields take that many bytes.
local widths = { uint8 = 1, uint16 = 2, uint24 = 3, uint32 = 4, int8 = 1, int16 = 2, int32 = 4 }
local integer_types = {}
for kind in pairs(widths) do integer_types[kind] = true end
widths.float = 4

-- `proto`'s fields, from rows { key, type, label, base, values, mask }: `type` names the
-- ProtoField constructor (uint8, bytes, float, bool...); the field's filter is `abbrev.<key>`, or
-- `abbrev.<filter>` where the row has one; an integer is shown in base.DEC unless the row says
-- otherwise. A row of type "checksum_status" is the Good / Bad of a checksum (add_checksum
-- fills it). Two kinds of row stand for several fields, their key for the list of them:
--   "bits", one flag per bit of a byte, bit 0 first: its `flags` are { name, label } each,
--     filtered as `abbrev.<filter or key>.<name>` (drivegate.add_bits);
--   "layout", the numbers of a block one after another: its `fields` are rows of their own, each
--     with its offset in the block, `at` (drivegate.add_layout).
-- A row may also be a list of rows. Sets proto.fields; returns key -> field.
function drivegate.fields(proto, abbrev, rows)
  local f, all = {}, {}
  local function add(r)
    if type(r[1]) == "table" then  -- a list of rows (drivegate.modbus_rtu_rows)
      for _, row in ipairs(r) do add(row) end
      return
    end
    local key, kind, label = r[1], r[2], r[3]
    local filter = abbrev .. "." .. (r.filter or key)
    if kind == "bits" then
      f[key] = {}
      for i, flag in ipairs(r.flags) do
        local pf = ProtoField.bool(filter .. "." .. flag[1], flag[2], 8, nil, lshift(1, i - 1))
        f[key][i] = pf
        all[#all + 1] = pf
      end
    elseif kind == "checksum_status" then
      f[key] = ProtoField.uint8(filter, label, base.DEC, drivegate.checksum_status)
      all[#all + 1] = f[key]
    elseif kind == "layout" then
      f[key] = {}
      for _, field in ipairs(r.fields) do
        f[key][#f[key] + 1] = { add(field), field.at, widths[field[2]] }
      end
    else
      local display = r[4]
      if display == nil and integer_types[kind] then display = base.DEC end
      f[key] = ProtoField[kind](filter, label, display, r[5], r[6])
      all[#all + 1] = f[key]
    end
    return f[key]
  end
  for _, r in ipairs(rows) do add(r) end
  proto.fields = all
  return f
end

-- The rows (drivegate.fields) of a Modbus RTU frame's address and function code, its exception
-- bit apart (MODBUS over Serial Line V1.02, 2.5.1; Application Protocol V1.1b3, 7: an exception
-- reply's function code is the request's + 0x80), `functions` naming the codes.
function drivegate.modbus_rtu_rows(functions)
  return {
    { "address", "uint8", "Address" },
    { "func", "uint8", "Function", base.HEX, functions, 0x7F, filter = "function" },
    { "exception_flag", "bool", "Exception", 8, nil, 0x80, filter = "exception" },
  }
end

-- Each flag of a "bits" row (drivegate.fields) under `tree`, over the byte `range`.
function drivegate.add_bits(tree, flags, range)
  for _, flag in ipairs(flags) do tree:add(flag, range) end
end

-- Each field of a "layout" row (drivegate.fields) under `tree`, at its offset from `from`.
function drivegate.add_layout(tree, tvb, from, layout)
  for _, l in ipairs(layout) do tree:add(l[1], tvb(from + l[2], l[3])) end
end

-- The tree of one frame of `proto`, its name in the Protocol column, and the frame's length; the
-- tree is nil when the frame is shorter than `min_len` bytes, which are then shown as
-- `data_field` with the expert `e_short`.
function drivegate.frame_tree(proto, column, tvb, pinfo, tree, min_len, data_field, e_short)
  pinfo.cols.protocol = column
  local t = tree:add(proto, tvb())
  local len = tvb:len()
  if len >= min_len then return t, len end
  t:add(data_field, tvb())
  t:add_proto_expert_info(e_short)
  return nil, len
end

-- The two experts of a protocol's frames, set as `proto`'s: a bad checksum (an error) and a
-- frame of the wrong length or shape (a warning). Returned in that order.
function drivegate.experts(proto, bad_abbrev, bad_text, shape_abbrev, shape_text)
  local e_bad = ProtoExpert.new(bad_abbrev, bad_text, expert.group.CHECKSUM, expert.severity.ERROR)
  local e_shape = ProtoExpert.new(shape_abbrev, shape_text, expert.group.PROTOCOL,
                                  expert.severity.WARN)
  proto.experts = { e_bad, e_shape }
  return e_bad, e_shape
end

-- Big-endian 16-bit words of tvb[from, to) as `word_field`, an odd last byte as `data_field`.
function drivegate.words(t, tvb, from, to, word_field, data_field)
  local i = from
  while i + 1 < to do
    t:add(word_field, tvb(i, 2))
    i = i + 2
  end
  if i < to then t:add(data_field, tvb(i, to - i)) end
end

-- A Modbus request's start address and quantity (MODBUS Application Protocol V1.1b3, 6.x: the
-- two words after the function code, tvb[2, 6)) as `start_field` and `quantity_field`; the Info
-- column's text of them, `format` given the two.
function drivegate.start_quantity(tree, tvb, start_field, quantity_field, format)
  tree:add(start_field, tvb(2, 2))
  tree:add(quantity_field, tvb(4, 2))
  return string.format(format, tvb(2, 2):uint(), tvb(4, 2):uint())
end

-- The bytes of tvb[1, len - 1), between a frame's two flags, unstuffed: an `escape` byte and the
-- one after it stand for that one XOR `escape_xor` (a nil `escape`: nothing is stuffed). A
-- ByteArray, or nil when the byte before the end flag is an escape.
function drivegate.unstuff(tvb, escape, escape_xor)
  local len = tvb:len()
  local out = ByteArray.new()
  local i = 1
  while i < len - 1 do
    local b = tvb(i, 1):uint()
    if b == escape then
      if i + 1 >= len - 1 then return nil end
      b = bxor(tvb(i + 1, 1):uint(), escape_xor)
      i = i + 1
    end
    out:append(ByteArray.new(string.format("%02x", b)))
    i = i + 1
  end
  return out
end

-- CRC-16 of Modbus (MODBUS over Serial Line V1.02, 6.2.2: init FFFF, polynomial A001 reflected)
-- over tvb[0, len).
local function crc16_modbus(tvb, len)
  local crc = 0xFFFF
  for i = 0, len - 1 do
    crc = bxor(crc, tvb(i, 1):uint())
    for _ = 1, 8 do
      if band(crc, 1) ~= 0 then crc = bxor(rshift(crc, 1), 0xA001) else crc = rshift(crc, 1) end
    end
  end
  return crc
end

-- The Modbus CRC-16 that ends a frame of `len` bytes, verified (drivegate.add_checksum): it
-- covers every byte before it and is sent low byte first.
function drivegate.add_crc16_modbus(tree, pinfo, field, status_field, expert_bad, tvb, len)
  return drivegate.add_checksum(tree, pinfo, field, status_field, expert_bad, tvb(len - 2, 2),
                                crc16_modbus(tvb, len - 2), true)
end

-- XOR of the bytes of `tvb` in [from, from + len).
function drivegate.xor(tvb, from, len)
  local x = 0
  for i = from, from + len - 1 do x = bxor(x, tvb(i, 1):uint()) end
  return x
end

-- A checksum field and its generated status (Good / Bad), with an expert item on a mismatch.
drivegate.checksum_status = { [0] = "Bad", [1] = "Good", [2] = "Unverified" }
-- `le`: the checksum is sent low byte first.
function drivegate.add_checksum(tree, pinfo, field, status_field, expert_bad, range, expected, le)
  local got = le and range:le_uint() or range:uint()
  local item = le and tree:add_le(field, range) or tree:add(field, range)
  local ok = got == expected
  local st = item:add(status_field, ok and 1 or 0):set_generated()
  if not ok then
    item:append_text(string.format(" [incorrect, should be 0x%0" .. (range:len() * 2) .. "x]",
                                   expected))
    item:add_proto_expert_info(expert_bad,
                               string.format("Bad checksum: 0x%x, should be 0x%x", got, expected))
  else
    item:append_text(" [correct]")
  end
  return ok
end

if not drivegate.first_load("drivegate") then return end

local p = Proto("drivegate", "drivegate capture pseudo-header")

local directions = { [0] = "gateway -> drive", [1] = "drive -> gateway" }
local f = drivegate.fields(p, "drivegate", {
  { "version", "uint8", "Version" },
  { "direction", "uint8", "Direction", base.DEC, directions },
  { "flags", "uint8", "Flags", base.HEX },
  { "flag_bits", "bits", filter = "flags", flags = {  -- docs/capture.md: 0x01, 0x02 ... 0x20
    { "bad_checksum", "Bad checksum (station's verdict)" },
    { "noise", "Noise (not a frame)" },
    { "nack", "NACK" },
    { "foreign", "Foreign (not for us)" },
    { "echo", "Echo mismatch" },
    { "retry", "Resend" },
  } },
  { "unit", "uint8", "Unit id", filter = "unit_id" },
  { "adapter_len", "uint8", "Adapter id length" },
  { "adapter", "string", "Adapter id" },
  { "device_len", "uint8", "Device name length" },
  { "device", "string", "Device" },
  { "noise_data", "bytes", "Noise" },
})

local e_short = ProtoExpert.new("drivegate.short", "Truncated pseudo-header",
                                expert.group.MALFORMED, expert.severity.ERROR)
local e_version = ProtoExpert.new("drivegate.version.unknown", "Unknown pseudo-header version",
                                  expert.group.PROTOCOL, expert.severity.WARN)
local e_noise = ProtoExpert.new("drivegate.noise.expert", "Bytes the gateway could not place",
                                expert.group.SEQUENCE, expert.severity.NOTE)
local e_unknown = ProtoExpert.new("drivegate.adapter.unknown", "No dissector for this adapter",
                                  expert.group.UNDECODED, expert.severity.NOTE)
p.experts = { e_short, e_version, e_noise, e_unknown }

-- Adapter id -> dissector; the protocol files add themselves.
local adapters = DissectorTable.new("drivegate.adapter", "drivegate adapter id", ftypes.STRING)

function p.dissector(tvb, pinfo, tree)
  local len = tvb:len()
  local t = tree:add(p, tvb(), "drivegate capture")
  if len < 6 then
    t:add_proto_expert_info(e_short)
    return len
  end
  local version = tvb(0, 1):uint()
  t:add(f.version, tvb(0, 1))
  if version ~= 1 then
    t:add_proto_expert_info(e_version)
    return len
  end
  local dir = tvb(1, 1):uint()
  t:add(f.direction, tvb(1, 1))
  local flags = tvb(2, 1):uint()
  drivegate.add_bits(t:add(f.flags, tvb(2, 1)), f.flag_bits, tvb(2, 1))
  t:add(f.unit, tvb(3, 1))
  local alen = tvb(4, 1):uint()
  t:add(f.adapter_len, tvb(4, 1))
  if len < 6 + alen then
    t:add_proto_expert_info(e_short)
    return len
  end
  local adapter = alen > 0 and tvb(5, alen):string() or ""
  if alen > 0 then t:add(f.adapter, tvb(5, alen)) end
  local dlen = tvb(5 + alen, 1):uint()
  t:add(f.device_len, tvb(5 + alen, 1))
  local hlen = 6 + alen + dlen
  if len < hlen then
    t:add_proto_expert_info(e_short)
    return len
  end
  local device = dlen > 0 and tvb(6 + alen, dlen):string() or ""
  if dlen > 0 then t:add(f.device, tvb(6 + alen, dlen)) end
  t:set_len(hlen)
  t:append_text(string.format(", %s, %s (%s)", directions[dir] or "?", device, adapter))

  pinfo.p2p_dir = (dir == 0) and 0 or 1  -- P2P_DIR_SENT: ours; P2P_DIR_RECV: the drive's
  if dir == 0 then
    pinfo.cols.src = "gateway"
    pinfo.cols.dst = device ~= "" and device or "bus"
  else
    pinfo.cols.src = device ~= "" and device or "bus"
    pinfo.cols.dst = "gateway"
  end
  pinfo.cols.protocol = "drivegate"
  if len == hlen then return len end
  local frame = tvb(hlen):tvb()
  if band(flags, 0x02) ~= 0 then  -- noise: not a frame; shown raw, never decoded
    pinfo.cols.info = string.format("Noise, %d bytes", len - hlen)
    local it = tree:add(f.noise_data, tvb(hlen))
    it:add_proto_expert_info(e_noise)
    return len
  end
  local d = adapters:get_dissector(adapter)
  if d == nil then
    tree:add_proto_expert_info(e_unknown)
    Dissector.get("data"):call(frame, pinfo, tree)
    return len
  end
  d:call(frame, pinfo, tree)
  return len
end

DissectorTable.get("wtap_encap"):add(wtap.USER0, p)

-- The adapters' dissectors, found by a rule, never listed: in the source tree (this file is
-- tools/wireshark/drivegate.lua) every adapters/<id>/dissector.lua; then every drivegate_*.lua
-- beside this file: a plugin folder (the build's build/wireshark/, or installed) holds each
-- adapter's as drivegate_<id>.lua and each described protocol's data as
-- drivegate_framed_<NAME>.lua, unless Wireshark loads them itself from its plugin folder. Each
-- loads once, however it is found.
local here = (debug and debug.getinfo(1, "S").source or ""):match("^@(.*[/\\])") or ""
local function load(path)
  local fh = io.open(path, "r")
  if fh then
    fh:close()
    dofile(path)
  end
end
local function entries(dir, ext)
  local names = {}
  if Dir and Dir.exists(dir) then
    for name in Dir.open(dir, ext) do names[#names + 1] = name end
  end
  table.sort(names)
  return names
end
if here ~= "" then
  if here:match("tools[/\\]wireshark[/\\]$") then
    local adapters_dir = here .. "../../adapters"
    for _, id in ipairs(entries(adapters_dir)) do
      load(adapters_dir .. "/" .. id .. "/dissector.lua")
    end
  end
  for _, name in ipairs(entries(here, ".lua")) do
    if name:match("^drivegate_.+%.lua$") then load(here .. name) end
  end
end
