-- wrk script: POSTs the photos listed in the arguments as raw image/jpeg bodies, in
-- turn, and tallies the response status codes.
local bodies = {}
local next_body = 0
statuses = {}

function init(args)
  for _, path in ipairs(args) do
    local f = assert(io.open(path, "rb"))
    bodies[#bodies + 1] = f:read("*a")
    f:close()
  end
end

function request()
  next_body = next_body % #bodies + 1
  return wrk.format("POST", "/segment?format=png", { ["Content-Type"] = "image/jpeg" }, bodies[next_body])
end

function response(status, headers, body)
  statuses[status] = (statuses[status] or 0) + 1
end

local threads = {}
function setup(thread)
  threads[#threads + 1] = thread
end

function done(summary, latency, requests)
  local total = {}
  for _, t in ipairs(threads) do
    for status, n in pairs(t:get("statuses")) do
      total[status] = (total[status] or 0) + n
    end
  end
  local parts = {}
  for status, n in pairs(total) do
    parts[#parts + 1] = string.format("%d: %d", status, n)
  end
  table.sort(parts)
  io.write(string.format("statuses { %s }\n", table.concat(parts, ", ")))
  io.write(string.format("summary p50 %.1f ms  p99 %.1f ms  %.1f req/s\n",
    latency:percentile(50) / 1000, latency:percentile(99) / 1000,
    summary.requests / (summary.duration / 1e6)))
end
