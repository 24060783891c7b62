// piezoid dashboard: polls the dashboard server's JSON (api/state, api/curve) and draws the jobs,
// the selected job's fitness curve (best and median cost per generation) and the workers.
// Read-only: it only GETs. The access token, if any, comes from the page's own ?token=.
'use strict';

const query = new URLSearchParams(location.search);
const token = query.get('token');
const POLL_MS = Number(query.get('poll_ms') || 1000);

function withToken(path) {
  if (!token) return path;
  return path + (path.includes('?') ? '&' : '?') + 'token=' + encodeURIComponent(token);
}
async function api(path) {
  const r = await fetch(withToken(path), {cache: 'no-store'});
  if (!r.ok) throw new Error(path + ': HTTP ' + r.status + ' ' + (await r.text()));
  return r.json();
}
const num = v => Number(v);  // protobuf's JSON gives 64-bit integers as strings

function fmtCost(v) {
  const x = Number(v);
  if (!isFinite(x)) return String(v);
  if (x !== 0 && (Math.abs(x) >= 1e5 || Math.abs(x) < 1e-3)) return x.toExponential(3);
  return x.toPrecision(5);
}
function fmtDuration(s) {
  s = Number(s);
  if (!(s >= 0)) return '';
  if (s < 60) return s.toFixed(1) + ' s';
  if (s < 3600) return Math.floor(s / 60) + ' min ' + Math.round(s % 60) + ' s';
  return Math.floor(s / 3600) + ' h ' + Math.round((s % 3600) / 60) + ' min';
}
function fmtTime(unix) {
  const x = Number(unix);
  return x > 0 ? new Date(x * 1000).toLocaleTimeString() : '';
}
function el(tag, attrs, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) {
    if (k === 'class')
      e.className = v;
    else if (k.startsWith('data-'))
      e.setAttribute(k, v);
    else
      e[k] = v;
  }
  for (const c of children) e.append(c instanceof Node ? c : document.createTextNode(String(c)));
  return e;
}
function td(text, cls) {
  return el('td', cls ? {class: cls} : {}, text);
}
function replaceRows(tbody, rows) {
  tbody.replaceChildren(...rows);
}

let selected = query.get('job');  // the job whose curve is drawn
let userSelected = !!selected;
let curve = {job: null, records: []};
let chart = null;
let polls = 0, curveUpdates = 0, workerUpdates = 0, lastWorkerSig = '';

function renderJobs(state) {
  const jobs = state.jobs || [];
  document.getElementById('jobs-empty').style.display = jobs.length ? 'none' : '';
  if (!userSelected) {  // follow the first running job, else the first job
    const running = jobs.find(j => j.state === 'JOB_STATE_RUNNING');
    const pick = running || jobs[0];
    if (pick) selected = pick.job_id;
  }
  const rows = jobs.map(j => {
    // JobInfo.generation counts the generations done, 0 included: the last one is generation − 1.
    const done = num(j.generation), gen = j.algorithm === 'ga' ? Math.max(0, done - 1) : done;
    const max = num(j.max_generations);
    const frac = max > 0 ? Math.min(1, gen / max) : 0;
    const bar = el('span', {class: 'bar'}, el('span', {style: ''}));
    bar.firstChild.style.width = (100 * frac).toFixed(1) + '%';
    const final = j.state !== 'JOB_STATE_RUNNING';
    const report = final && !j.archived ?
        el('a', {href: withToken('jobs/' + encodeURIComponent(j.job_id) + '/report/')}, 'report') :
        el('span', {class: 'empty'}, final ? 'archived' : 'when it ends');
    const notes = [j.message, j.notice, j.storage_error].filter(Boolean).join(' · ');
    const state =
        el('td', {class: 'state-' + j.state}, j.state.replace('JOB_STATE_', '').toLowerCase());
    if (notes) state.append(el('div', {class: 'notice wrap'}, notes));
    const tr =
        el('tr', {class: 'job' + (j.job_id === selected ? ' selected' : ''), 'data-job': j.job_id},
           td(j.job_id), td(j.name, 'wrap'), td(j.kind), state, el('td', {}, bar),
           td(gen + (max > 0 ? ' / ' + max : ''), 'num'), td(fmtCost(j.best_cost), 'num'),
           td(num(j.evaluations).toLocaleString(), 'num'), td(fmtDuration(j.elapsed_s), 'num'),
           td((j.quarantined || []).length, 'num'), el('td', {}, report));
    tr.addEventListener('click', () => {
      selected = j.job_id;
      userSelected = true;
      tick(true);
    });
    return tr;
  });
  replaceRows(document.querySelector('#jobs tbody'), rows);
}

function renderWorkers(state) {
  const w = state.workers || {};
  const workers = w.workers || [];
  document.getElementById('workers-error').textContent = state.workers_error || '';
  document.getElementById('workers-empty').style.display = workers.length ? 'none' : '';
  let threads = 0, rate = 0, done = 0;
  const rows = workers.map(x => {
    const t = num(x.threads), item = Number(x.item_seconds);
    const speed = item > 0 ? t / item : NaN;
    threads += t;
    if (isFinite(speed)) rate += speed;
    done += num(x.tasks_done);
    const host = td((x.host || '?') + ' / ' + x.pid);
    host.title = x.arithmetic ? 'arithmetic: ' + x.arithmetic : '';
    return el(
        'tr', {'data-worker': x.id}, td(x.id.slice(-8) + (x.solo ? ' (suspect alone)' : '')), host,
        td(t, 'num'), td(isFinite(speed) ? speed.toFixed(0) : 'measuring', 'num'),
        td(num(x.leases), 'num'), td(num(x.tasks_in_flight), 'num'),
        td(num(x.tasks_done).toLocaleString(), 'num'), td(fmtTime(x.connected_unix_s)));
  });
  replaceRows(document.querySelector('#workers tbody'), rows);
  document.getElementById('workers-sum').textContent = workers.length ? workers.length +
          ' workers, ' + threads + ' threads, ≈ ' + rate.toFixed(0) + ' evaluations/s' :
                                                                        '';
  const sig = workers.map(x => x.id + ':' + x.tasks_done + ':' + x.leases).join(',');
  if (sig !== lastWorkerSig) {
    if (lastWorkerSig !== '') workerUpdates++;
    lastWorkerSig = sig;
  }
  document.body.dataset.workers = workers.length;
  document.body.dataset.workerThreads = threads;
  document.body.dataset.workerTasksDone = done;
  document.body.dataset.workerUpdates = workerUpdates;
}

function renderFailures(state) {
  const rows = [];
  for (const d of ((state.workers || {}).departed || []).slice().reverse())
    rows.push(
        el('tr', {}, td(fmtTime(d.at_unix_s)), td('worker ' + d.id.slice(-8) + ' left'),
           td(d.reason + ' (' + (d.host || '?') + ' / ' + d.pid + ', ' + num(d.tasks_done) +
              ' tasks done)')));
  for (const j of state.jobs || [])
    for (const q of j.quarantined || [])
      rows.push(
          el('tr', {}, td('generation ' + num(q.generation)),
             td('job ' + j.job_id + ': individual ' + q.index + ' quarantined'),
             td(num(q.strikes) + ' isolated worker deaths or hangs')));
  replaceRows(document.querySelector('#failures tbody'), rows);
  document.getElementById('failures-empty').style.display = rows.length ? 'none' : '';
}

function renderReports(state) {
  const reports = state.reports || [];
  document.getElementById('reports-section').style.display = reports.length ? '' : 'none';
  replaceRows(
      document.getElementById('reports'),
      reports.map(
          r => el(
              'li', {}, el('a', {href: withToken('reports/' + encodeURIComponent(r) + '/')}, r))));
}

function drawChart() {
  const recs = curve.records;
  const best = recs.map(r => ({x: num(r.generation), y: Number(r.best_cost)}));
  const median = recs.map(r => ({x: num(r.generation), y: Number(r.median_cost)}));
  // A job of several islands: the band from the best to the worst of the islands' bests.
  const islandBests = r => (r.islands || []).map(i => Number(i.best_cost || 0));
  const band = recs.filter(r => (r.islands || []).length > 1)
                   .map(r => ({x: num(r.generation), y: Math.max(...islandBests(r))}));
  const positive = recs.every(r => Number(r.best_cost) > 0 && Number(r.median_cost) > 0);
  const yType = positive && recs.length ? 'logarithmic' : 'linear';
  if (!chart) {
    chart = new Chart(document.getElementById('chart'), {
      type: 'line',
      data: {
        datasets: [
          {
            label: 'best cost',
            data: best,
            borderColor: '#1a6fc4',
            backgroundColor: '#1a6fc4',
            pointRadius: 0,
            borderWidth: 2
          },
          {
            label: 'median cost',
            data: median,
            borderColor: '#e08a1e',
            backgroundColor: '#e08a1e',
            pointRadius: 0,
            borderWidth: 1.5
          },
          {
            label: 'islands (best … worst island best)',
            data: band,
            borderColor: 'rgba(26,111,196,0.35)',
            backgroundColor: 'rgba(26,111,196,0.15)',
            pointRadius: 0,
            borderWidth: 1,
            fill: {target: 0},
            hidden: !band.length
          },
        ]
      },
      options: {
        animation: false,
        parsing: false,
        normalized: true,
        maintainAspectRatio: false,
        interaction: {mode: 'nearest', axis: 'x', intersect: false},
        scales: {
          x: {type: 'linear', title: {display: true, text: 'generation'}},
          y: {type: yType, title: {display: true, text: 'cost'}}
        },
      },
    });
  } else {
    chart.data.datasets[0].data = best;
    chart.data.datasets[1].data = median;
    chart.data.datasets[2].data = band;
    chart.data.datasets[2].hidden = !band.length;
    chart.options.scales.y.type = yType;
    chart.update('none');
  }
  document.getElementById('chart-job').textContent = curve.job || '—';
  const last = recs[recs.length - 1];
  document.getElementById('chart-info').textContent = last ?
      '(generation ' + num(last.generation) + ': best ' + fmtCost(last.best_cost) + ', median ' +
          fmtCost(last.median_cost) + ', ' + num(last.errors) + ' failed evaluations' +
          ((last.islands || []).length > 1 ? ', ' + last.islands.length +
                   ' islands, best in island ' + num(last.best_island || 0) :
                                             '') +
          ')' :
      '(no generation yet)';
  document.body.dataset.curveJob = curve.job || '';
  document.body.dataset.curvePoints = recs.length;
  document.body.dataset.curveLastGeneration = last ? num(last.generation) : -1;
  document.body.dataset.curveUpdates = curveUpdates;
}

async function refreshCurve() {
  if (!selected) return;
  if (curve.job !== selected) curve = {job: selected, records: []};
  const n = curve.records.length;
  const from = n ? num(curve.records[n - 1].generation) + 1 : 0;
  const c = await api('api/curve?job=' + encodeURIComponent(selected) + '&from=' + from);
  if (c.job_id !== curve.job) return;  // the selection changed meanwhile
  for (const r of c.records || []) curve.records.push(r);
  if (curve.records.length > n && n > 0) curveUpdates++;
  drawChart();
}

let timer = null;
async function tick(once) {
  clearTimeout(timer);
  try {
    const state = await api('api/state');
    polls++;
    document.getElementById('master').textContent = state.master;
    document.getElementById('poll').textContent = state.error ?
        'master not answering: ' + state.error :
        'updated ' + fmtTime(state.polled_unix_s);
    document.getElementById('poll').className = state.error ? 'error' : 'muted';
    const spec = state.workers ? num(state.workers.speculative_leases) : 0;
    document.getElementById('uptime').textContent =
        (state.workers && Number(state.workers.uptime_s) > 0 ?
             'master up ' + fmtDuration(state.workers.uptime_s) :
             '') +
        (spec > 0 ? ' · stragglers: ' + spec + ' copies sent, ' +
                 num(state.workers.speculative_wins) + ' answered first' :
                    '');
    renderJobs(state);
    renderWorkers(state);
    renderFailures(state);
    renderReports(state);
    await refreshCurve();
    document.body.dataset.polls = polls;
  } catch (e) {
    document.getElementById('poll').textContent = 'dashboard not answering: ' + e.message;
    document.getElementById('poll').className = 'error';
  } finally {
    timer = setTimeout(tick, POLL_MS);
  }
}
tick();
