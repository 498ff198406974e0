-- mdriver-2400: the data adapters/framed/dissector.lua decodes it with, made by
-- `drivegate protocol dissector mdriver-2400` from its description: do not edit.
local p = {
  name = "mdriver-2400",
  summary = "compressor motor driver, sum-0x55 frames (Japanese spec, described)",
  framing = { max_frame = 15 },
  checks = {
    { name = "sum55", kind = "sum_to", width = 1, total = 85, poly = 0, init = 0, reflect_in = false, reflect_out = false, xor_out = 0, from = 0, to = nil, step = 1 },
  },
  messages = {
    { name = "check", direction = "request", size = 9, nack = false,
      tokens = {
        { offset = 0, width = 1, field = "master", encoding = "uint", le = false },
        { offset = 1, width = 1, field = "address", encoding = "uint", le = false },
        { offset = 2, width = 1, constant = 0, le = false },
        { offset = 3, width = 1, field = "n", encoding = "uint", le = false },
        { offset = 4, width = 1, constant = 1, le = false },
        { offset = 5, width = 1, constant = 18, le = false },
        { offset = 6, width = 1, constant = 0, le = false },
        { offset = 7, width = 1, constant = 6, le = false },
        { offset = 8, width = 1, check = 1, name = "cs", le = false },
      } },
    { name = "run", direction = "request", size = 8, nack = false,
      tokens = {
        { offset = 0, width = 1, field = "master", encoding = "uint", le = false },
        { offset = 1, width = 1, field = "address", encoding = "uint", le = false },
        { offset = 2, width = 1, constant = 16, le = false },
        { offset = 3, width = 1, field = "n", encoding = "uint", le = false },
        { offset = 4, width = 1, field = "code", encoding = "uint", le = false },
        { offset = 5, width = 1, field = "change", encoding = "uint", le = false },
        { offset = 6, width = 1, constant = 0, le = false },
        { offset = 7, width = 1, check = 1, name = "cs", le = false },
      } },
    { name = "check_reply", direction = "reply", size = 9, nack = false,
      tokens = {
        { offset = 0, width = 1, field = "address", encoding = "uint", le = false },
        { offset = 1, width = 1, field = "master", encoding = "uint", le = false },
        { offset = 2, width = 1, constant = 0, le = false },
        { offset = 3, width = 1, field = "n", encoding = "uint", le = false },
        { offset = 4, width = 4, field = "code", encoding = "uint", le = false },
        { offset = 8, width = 1, check = 1, name = "cs", le = false },
      } },
    { name = "run_reply", direction = "reply", size = 13, nack = false,
      tokens = {
        { offset = 0, width = 1, field = "address", encoding = "uint", le = false },
        { offset = 1, width = 1, field = "master", encoding = "uint", le = false },
        { offset = 2, width = 1, constant = 16, le = false },
        { offset = 3, width = 1, field = "n", encoding = "uint", le = false },
        { offset = 4, width = 1, field = "target_code", encoding = "uint", le = false },
        { offset = 5, width = 1, field = "actual_code", encoding = "uint", le = false },
        { offset = 6, width = 1, field = "reserved", encoding = "uint", le = false },
        { offset = 7, width = 1, field = "error_code", encoding = "uint", le = false },
        { offset = 8, width = 1, field = "ipm_temperature", encoding = "uint", le = false },
        { offset = 9, width = 1, field = "info_1", encoding = "uint", le = false },
        { offset = 10, width = 1, field = "info_2", encoding = "uint", le = false },
        { offset = 11, width = 1, field = "info_3", encoding = "uint", le = false },
        { offset = 12, width = 1, check = 1, name = "cs", le = false },
      } },
  },
}
local drivegate = _G.drivegate or { loaded = {} }
_G.drivegate = drivegate
drivegate.framed_protocols = drivegate.framed_protocols or {}
if drivegate.framed_protocols[p.name] then return end
drivegate.framed_protocols[p.name] = p
if drivegate.framed_register then drivegate.framed_register(p) end
