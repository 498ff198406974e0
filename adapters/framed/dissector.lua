-- framed: every described protocol (docs/protocols.md), decoded from its description's data.
-- One dissector reads them all: each description's data (`drivegate protocol dissector NAME`,
-- drivegate_framed_NAME.lua in the plugin folder; the build makes the shipped descriptions' in
-- build/wireshark/) hands itself to it, and it registers a protocol `framed_NAME` under the
-- adapter id "framed/NAME" a capture names a described device's frames with. A frame is the first
-- message of its direction whose size and constants it fits (unstuffed between the flags, where
-- the framing stuffs); each field is shown by its name, each check verified into
-- framed_NAME.checksum.status (1 Good, 0 Bad, with an expert error on a mismatch).
local drivegate = _G.drivegate
if not drivegate.first_load("framed") then return end
local band, bor, bxor = drivegate.band, drivegate.bor, drivegate.bxor
local lshift, rshift = drivegate.lshift, drivegate.rshift

local function reflect(v, bits)
  local r = 0
  for _ = 1, bits do
    r = bor(lshift(r, 1), band(v, 1))
    v = rshift(v, 1)
  end
  return r
end

-- A check's value over bytes[from .. to) (0-based, every `step`-th), as the C++ codec computes it.
local function check_value(c, bytes, from, to)
  local width_mask = c.width >= 4 and 0xFFFFFFFF or (lshift(1, 8 * c.width) - 1)
  local acc = 0
  if c.kind == "xor" then
    for i = from, to - 1, c.step do acc = bxor(acc, bytes[i]) end
    return acc
  end
  if c.kind == "crc" then
    local bits = 8 * c.width
    local top = lshift(1, bits - 1)
    local crc = band(c.init, width_mask)
    for i = from, to - 1, c.step do
      local b = bytes[i]
      if c.reflect_in then b = reflect(b, 8) end
      crc = bxor(crc, lshift(b, bits - 8))
      for _ = 1, 8 do
        if band(crc, top) ~= 0 then
          crc = band(bxor(lshift(crc, 1), c.poly), width_mask)
        else
          crc = band(lshift(crc, 1), width_mask)
        end
      end
    end
    if c.reflect_out then crc = reflect(crc, bits) end
    return band(bxor(crc, c.xor_out), width_mask)
  end
  for i = from, to - 1, c.step do acc = acc + bytes[i] end
  if c.kind == "sum" then return acc % (width_mask + 1) end
  if c.kind == "sum_to" then return (c.total - acc) % (width_mask + 1) end
  if c.kind == "lrc" then return (-(acc % 256)) % 256 end
  return (-acc) % (width_mask + 1)  -- twos_complement
end

-- The bytes between the flags, unstuffed: a ByteArray, or nil and why.
local function unstuff(p, tvb)
  local f = p.framing
  if tvb:len() < 2 or tvb(0, 1):uint() ~= f.start then return nil, "no start flag" end
  local out = drivegate.unstuff(tvb, f.escape, f.escape_xor)
  if not out then return nil, "an escape at the end" end
  return out
end

local function register(p)
  local abbrev = "framed_" .. p.name:gsub("[^%w]", "_")
  local proto = Proto(abbrev, p.name .. " (described; drivegate framed)")
  local fields = {
    message = ProtoField.string(abbrev .. ".message", "Message"),
    constant = ProtoField.uint8(abbrev .. ".constant", "Constant", base.HEX),
    checksum = ProtoField.uint32(abbrev .. ".checksum", "Checksum", base.HEX),
    status = ProtoField.uint8(abbrev .. ".checksum.status", "Checksum status", base.DEC,
                              drivegate.checksum_status),
    unknown = ProtoField.bytes(abbrev .. ".unknown", "No message of the description fits"),
  }
  local list = { fields.message, fields.constant, fields.checksum, fields.status, fields.unknown }
  -- One field per name and encoding: a name means the same in every message that has it.
  local by_name = {}
  for _, m in ipairs(p.messages) do
    for _, t in ipairs(m.tokens) do
      if t.field then
        local key = t.field .. ":" .. t.encoding
        if not by_name[key] then
          local filter = abbrev .. "." .. t.field
          if by_name[t.field .. ":seen"] then filter = filter .. "_" .. t.encoding end
          local pf
          if t.encoding == "f32" then
            pf = ProtoField.float(filter, t.field)
          elseif t.encoding == "int" then
            pf = ProtoField.int32(filter, t.field, base.DEC)
          else
            pf = ProtoField.uint32(filter, t.field, base.DEC)
          end
          by_name[key] = pf
          by_name[t.field .. ":seen"] = true
          list[#list + 1] = pf
        end
      end
    end
  end
  proto.fields = list
  local e_bad = ProtoExpert.new(abbrev .. ".checksum.bad", "Bad checksum", expert.group.CHECKSUM,
                                expert.severity.ERROR)
  local e_unknown = ProtoExpert.new(abbrev .. ".unknown.expert", "No message of the description fits",
                                    expert.group.MALFORMED, expert.severity.WARN)
  local e_stuffing = ProtoExpert.new(abbrev .. ".stuffing", "Bad flags or stuffing",
                                     expert.group.MALFORMED, expert.severity.ERROR)
  proto.experts = { e_bad, e_unknown, e_stuffing }
  local column = p.name:upper()

  function proto.dissector(tvb, pinfo, tree)
    pinfo.cols.protocol = column
    local t = tree:add(proto, tvb())
    local body = tvb
    if p.framing.start then
      local bytes, why = unstuff(p, tvb)
      if not bytes then
        t:add_proto_expert_info(e_stuffing, why)
        return tvb:len()
      end
      body = bytes:tvb("Unstuffed")
    end
    local len = body:len()
    local direction = pinfo.p2p_dir == 0 and "request" or "reply"
    local bytes = {}
    for i = 0, len - 1 do bytes[i] = body(i, 1):uint() end
    local found
    for _, m in ipairs(p.messages) do
      if m.direction == direction and m.size == len then
        local fits = true
        for _, tok in ipairs(m.tokens) do
          if tok.constant and bytes[tok.offset] ~= tok.constant then
            fits = false
            break
          end
        end
        if fits then
          found = m
          break
        end
      end
    end
    if not found then
      pinfo.cols.info = "Unknown frame, " .. len .. " bytes"
      t:add(fields.unknown, body()):add_proto_expert_info(e_unknown)
      return tvb:len()
    end
    pinfo.cols.info = found.name
    t:add(fields.message, found.name):set_generated()
    local first_check = found.size
    for _, tok in ipairs(found.tokens) do
      if tok.check and tok.offset < first_check then first_check = tok.offset end
    end
    for _, tok in ipairs(found.tokens) do
      local range = body(tok.offset, tok.width)
      if tok.constant then
        t:add(fields.constant, range)
      elseif tok.field then
        local pf = by_name[tok.field .. ":" .. tok.encoding]
        if tok.le then t:add_le(pf, range) else t:add(pf, range) end
      else
        local c = p.checks[tok.check]
        local n = len
        local from = c.from >= 0 and c.from or n + c.from
        local to = first_check
        if c.to then to = c.to >= 0 and c.to or n + c.to end
        from = math.max(0, math.min(from, n))
        to = math.max(from, math.min(to, n))
        local item = drivegate.add_checksum(t, pinfo, fields.checksum, fields.status, e_bad, range,
                                            check_value(c, bytes, from, to), tok.le)
        if not item then pinfo.cols.info = found.name .. " [bad " .. tok.name .. "]" end
      end
    end
    return tvb:len()
  end

  DissectorTable.get("drivegate.adapter"):add("framed/" .. p.name, proto)
end

drivegate.framed_register = register
drivegate.framed_protocols = drivegate.framed_protocols or {}
for _, p in pairs(drivegate.framed_protocols) do register(p) end
