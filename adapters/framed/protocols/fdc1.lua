-- fdc1: the data adapters/framed/dissector.lua decodes it with, made by
-- `drivegate protocol dissector fdc1` from its description: do not edit.
local p = {
  name = "fdc1",
  summary = "FDC1 12-42 V DC compressor controller, protocol v2 (streaming, described)",
  framing = { max_frame = 8 },
  checks = {
    { name = "even", kind = "xor", width = 1, total = 0, poly = 0, init = 0, reflect_in = false, reflect_out = false, xor_out = 0, from = 1, to = nil, step = 2 },
    { name = "odd", kind = "xor", width = 1, total = 0, poly = 0, init = 0, reflect_in = false, reflect_out = false, xor_out = 0, from = 0, to = nil, step = 2 },
    { name = "xor", kind = "xor", width = 1, total = 0, poly = 0, init = 0, reflect_in = false, reflect_out = false, xor_out = 0, from = 0, to = nil, step = 1 },
  },
  messages = {
    { name = "status_off", direction = "reply", size = 8, nack = false,
      tokens = {
        { offset = 0, width = 1, constant = 27, le = false },
        { offset = 1, width = 1, constant = 76, le = false },
        { offset = 2, width = 1, constant = 0, le = false },
        { offset = 3, width = 1, field = "alarm_code", encoding = "uint", le = false },
        { offset = 4, width = 2, field = "restart", encoding = "uint", le = false },
        { offset = 6, width = 1, check = 2, name = "co", le = false },
        { offset = 7, width = 1, check = 1, name = "ce", le = false },
      } },
    { name = "status_on", direction = "reply", size = 8, nack = false,
      tokens = {
        { offset = 0, width = 1, constant = 27, le = false },
        { offset = 1, width = 1, constant = 76, le = false },
        { offset = 2, width = 2, field = "rpm", encoding = "uint", le = false },
        { offset = 4, width = 2, field = "current", encoding = "uint", le = false },
        { offset = 6, width = 1, check = 2, name = "co", le = false },
        { offset = 7, width = 1, check = 1, name = "ce", le = false },
      } },
    { name = "speed", direction = "request", size = 8, nack = false,
      tokens = {
        { offset = 0, width = 1, constant = 72, le = false },
        { offset = 1, width = 1, constant = 115, le = false },
        { offset = 2, width = 2, field = "min", encoding = "uint", le = false },
        { offset = 4, width = 2, field = "max", encoding = "uint", le = false },
        { offset = 6, width = 1, constant = 85, le = false },
        { offset = 7, width = 1, check = 3, name = "x", le = false },
      } },
  },
}
local drivegate = _G.drivegate or { loaded = {} }
_G.drivegate = drivegate
drivegate.framed_protocols = drivegate.framed_protocols or {}
if drivegate.framed_protocols[p.name] then return end
drivegate.framed_protocols[p.name] = p
if drivegate.framed_register then drivegate.framed_register(p) end
