// The live page (docs/live.md): one self-contained HTML file with the vendored uPlot, like
// report.html, that follows /events and redraws at most 10 times a second. It draws the power
// deviation against the band (trip and back-off markers), the applied excitation, the
// estimates with their 2-sigma bands as they converge, the model's Bode plot with the
// swept-sine points, the phase with its ETA, the supervisor and the loop timing.
//
// For tests the body carries data-samples, data-last-t, data-phase, data-estimates,
// data-sweep-points, data-outcome, data-stream and data-js-error (read from a headless
// browser's DOM).
#include <fmt/format.h>

#include <string>

#include "rig/live/http_server.hpp"
#include "rig/report/uplot_assets.hpp"

namespace rig::live {
namespace {

constexpr const char* kStyle = R"css(
body{font:14px/1.4 system-ui,sans-serif;margin:16px;color:#222;background:#fafafa}
h1{font-size:20px;margin:0 0 8px}
#trip{white-space:normal}
#status{display:grid;grid-template-columns:repeat(auto-fill,minmax(150px,1fr));gap:6px;margin:8px 0}
.kv{background:#fff;border:1px solid #ddd;border-radius:4px;padding:4px 8px}
.kv b{display:block;font-size:11px;color:#666;font-weight:normal}
.kv span{font-size:16px;font-variant-numeric:tabular-nums}
#banner{padding:8px;border-radius:4px;margin:8px 0;display:none}
.ok{background:#e3f4e3;border:1px solid #7b7}.bad{background:#fbe3e3;border:1px solid #c77}
.grid{display:grid;grid-template-columns:repeat(auto-fill,minmax(460px,1fr));gap:12px}
.card{background:#fff;border:1px solid #ddd;border-radius:4px;padding:8px}
.card h2{font-size:14px;margin:0 0 4px}
#events{max-height:180px;overflow:auto;font:12px monospace;white-space:pre-wrap}
#stopbox{margin:8px 0}#stopmsg{margin-left:8px}
)css";

// The page's script: state from the stream, charts redrawn when something changed.
constexpr const char* kScript = R"js(
const S={start:null,state:null,t:[],dev:[],u:[],bo:[],est:[],bode:null,sweep:[],ev:[],
  timing:null,outcome:null};
let dirty=true;const C={};
const $=id=>document.getElementById(id);
window.onerror=(m)=>{document.body.dataset.jsError=String(m);};
const fmt=(x,d=2)=>x===null||x===undefined||!isFinite(x)?'-':Number(x).toFixed(d);
function kv(id,label){const d=document.createElement('div');d.className='kv';
  if(id==='trip')d.style.gridColumn='span 3';
  d.innerHTML='<b>'+label+'</b><span id="'+id+'">-</span>';$('status').appendChild(d);}
[['phase','phase'],['t','test time, s'],['eta','remaining, s'],['sup','supervisor'],
 ['p0','P0, kW'],['dev','deviation, % of P0'],['peak','peak in phase, %'],['bias','bias, %'],
 ['flags','flags'],['trip','trip'],['timing','loop lateness p50/p99/max, ms']].forEach(a=>kv(a[0],a[1]));
function chart(id,title,series,opts={}){
  const el=$(id);const o=Object.assign({title:title,width:el.clientWidth||460,height:220,
    scales:{x:{time:false}},series:[{label:opts.xl||'t, s'}].concat(series),
    axes:[{label:opts.xl||'test time, s'},{label:opts.yl||''}]},opts.extra||{});
  C[id]=new uPlot(o,[[]].concat(series.map(()=>[])),el);}
function bandHook(u){const b=S.state?S.state.band_pct:(S.start?S.start.band_pct:3);
  const ctx=u.ctx;ctx.save();ctx.strokeStyle='#c33';ctx.setLineDash([6,4]);
  for(const v of [b,-b]){const y=u.valToPos(v,'y',true);ctx.beginPath();
    ctx.moveTo(u.bbox.left,y);ctx.lineTo(u.bbox.left+u.bbox.width,y);ctx.stroke();}
  ctx.setLineDash([]);for(const e of S.ev){const trip=/trip|fault|abort/.test(e.kind);
    if(!trip&&e.kind!=='alarm')continue;ctx.strokeStyle=trip?'#c00':'#e80';
    const x=u.valToPos(e.t_s,'x',true);ctx.beginPath();ctx.moveTo(x,u.bbox.top);
    ctx.lineTo(x,u.bbox.top+u.bbox.height);ctx.stroke();}ctx.restore();}
chart('c_dev','Power deviation against the band (dashed: +-band; red: trip; orange: back-off)',
  [{label:'P - P0, % of P0',stroke:'#1f77b4'},{label:'backing off',stroke:'#e80',
   width:0,points:{show:true,size:4,fill:'#e80'}}],
  {yl:'% of P0',extra:{hooks:{draw:[bandHook]},scales:{x:{time:false},
   y:{range:(u,a,b)=>{const m=Math.max(Math.abs(a),Math.abs(b),
   (S.state?S.state.band_pct:3)*1.15);return[-m,m];}}}}});
chart('c_u','Applied excitation',[{label:'u, % of rated',stroke:'#2ca02c'}],{yl:'% of rated'});
const P=[['gain','K, kW/%','gain_std'],['fn_hz','fn, Hz','fn_hz_std'],['zeta','zeta','zeta_std'],
  ['delay_s','Td, s',null]];
for(const p of P)chart('c_'+p[0],p[1]+(p[2]?' (band: +-2 se)':''),[{label:p[1],stroke:'#1f77b4'},
  {label:'+2 se',stroke:'#9ac'},{label:'-2 se',stroke:'#9ac'}],{yl:p[1],
  extra:{bands:[{series:[2,3],fill:'rgba(31,119,180,0.15)'}]}});
const logx={x:{time:false,distr:3}};
chart('c_mag','Bode magnitude (line: latest model; dots: swept sine)',[{label:'model, dB',
  stroke:'#1f77b4',spanGaps:true},{label:'swept sine, dB',stroke:'#d62728',width:0,
  points:{show:true,size:7}}],{xl:'f, Hz',yl:'dB (kW per %)',extra:{scales:logx}});
chart('c_ph','Bode phase',[{label:'model, deg',stroke:'#1f77b4',spanGaps:true},
  {label:'swept sine, deg',stroke:'#d62728',width:0,points:{show:true,size:7}}],
  {xl:'f, Hz',yl:'deg',extra:{scales:logx}});
function estValue(m,key){if(key==='delay_s')return m.delay_s;return m.derived?m.derived[key]:null;}
function nearestPhase(p,ref){if(ref===null||ref===undefined)return p;
  return p+360*Math.round((ref-p)/360);}
function bodeData(){const f=new Set();const b=S.bode;if(b)b.f_hz.forEach(x=>f.add(x));
  S.sweep.forEach(p=>f.add(p.f_hz));const xs=[...f].sort((a,c)=>a-c);
  const mi=new Map(),pi=new Map();if(b)b.f_hz.forEach((x,i)=>{mi.set(x,b.mag_db[i]);pi.set(x,b.phase_deg[i]);});
  const sm=new Map(),sp=new Map();S.sweep.forEach(p=>{sm.set(p.f_hz,p.mag_db);
    let ref=null;if(b){let k=0;while(k<b.f_hz.length-1&&b.f_hz[k]<p.f_hz)k++;ref=b.phase_deg[k];}
    sp.set(p.f_hz,nearestPhase(p.phase_deg,ref));});
  const g=(m,x)=>m.has(x)?m.get(x):null;
  return[[xs,xs.map(x=>g(mi,x)),xs.map(x=>g(sm,x))],[xs,xs.map(x=>g(pi,x)),xs.map(x=>g(sp,x))]];}
// rig monitor: one chart per tracked value on the history's time axis, with its thresholds.
const TR={};
function trendSeries(name){if(!TR[name]){TR[name]={x:[],v:[],lo:[],hi:[]};
  const card=document.createElement('div');card.className='card';
  card.innerHTML='<div id="t_'+name+'"></div>';$('trends').appendChild(card);
  $('trendbox').style.display='block';
  chart('t_'+name,name+' (dashed: alarm thresholds)',[{label:name,stroke:'#1f77b4'},
    {label:'low',stroke:'#c33',dash:[6,4]},{label:'high',stroke:'#c33',dash:[6,4]}],
    {xl:'history time, h',yl:name});}return TR[name];}
function text(id,v){$(id).textContent=v;}
function redraw(){if(!dirty)return;dirty=false;const s=S.state;
  if(s){text('phase',s.phase);text('t',fmt(s.t_s,1));text('eta',fmt(s.eta_s,0));
    text('sup',s.supervisor);text('p0',fmt(s.p0_kw,1));text('dev',fmt(s.deviation_pct,3));
    text('peak',fmt(s.peak_deviation_pct,3));text('bias',fmt(s.bias_pct,3));
    text('flags',(s.flags||[]).join(', ')||'none');}
  const trip=S.ev.filter(e=>/trip|fault|abort/.test(e.kind)).pop();
  text('trip',trip?trip.kind+' at '+fmt(trip.t_s,1)+' s: '+trip.text:'none');
  if(S.timing)text('timing',fmt(S.timing.p50_ms,2)+' / '+fmt(S.timing.p99_ms,2)+' / '+
    fmt(S.timing.max_ms,1)+(S.timing.overruns?' ('+S.timing.overruns+' overruns)':''));
  C.c_dev.setData([S.t,S.dev,S.bo]);C.c_u.setData([S.t,S.u]);
  for(const p of P){const xs=[],v=[],hi=[],lo=[];for(const m of S.est){const x=estValue(m,p[0]);
    if(x===null||x===undefined)continue;const se=p[2]&&m.derived?m.derived[p[2]]:null;
    xs.push(m.t_s);v.push(x);hi.push(se!==null?x+2*se:null);lo.push(se!==null?x-2*se:null);}
    C['c_'+p[0]].setData([xs,v,hi,lo]);}
  const bd=bodeData();C.c_mag.setData(bd[0]);C.c_ph.setData(bd[1]);
  for(const n in TR){const t=TR[n];C['t_'+n].setData([t.x,t.v,t.lo,t.hi]);}
  document.body.dataset.trends=Object.keys(TR).length;
  $('events').textContent=S.ev.map(e=>'['+fmt(e.t_s,2).padStart(9)+' s] '+e.kind+': '+e.text).join('\n');
  const d=document.body.dataset;d.samples=S.t.length;d.lastT=S.t.length?S.t[S.t.length-1]:'';
  d.phase=s?s.phase:'';d.estimates=S.est.length;d.sweepPoints=S.sweep.length;d.events=S.ev.length;
  if(S.outcome){const o=S.outcome,bn=$('banner');bn.style.display='block';
    bn.className=o.exit_code===0?'ok':'bad';bn.textContent='Finished, exit '+o.exit_code+': '+
    o.outcome;d.outcome=o.exit_code;}}
const es=new EventSource('events');document.body.dataset.stream='connecting';
es.onopen=()=>{document.body.dataset.stream='open';};
es.onerror=()=>{document.body.dataset.stream=S.outcome?'closed':'reconnecting';};
const on=(k,f)=>es.addEventListener(k,e=>{f(JSON.parse(e.data));dirty=true;});
on('start',m=>{S.start=m;if(m.command==='monitor')document.querySelectorAll('.commission')
  .forEach(e=>{e.style.display='none';});});on('state',m=>{S.state=m;});on('timing',m=>{S.timing=m;});
const addSample=m=>{S.t.push(m.t_s);S.dev.push(m.deviation_pct);S.u.push(m.u_pct);
  S.bo.push(m.backoff?m.deviation_pct:null);};
on('sample',addSample);on('samples',a=>a.forEach(addSample));
on('event',m=>{S.ev.push(m);});
const alarm=k=>m=>{S.ev.push({t_s:m.t_s,kind:k,text:(m.cause||'')+(m.check?': check '+
  m.check:'')});};
on('alarm',alarm('alarm'));on('alarm_history',alarm('alarm (earlier run)'));
on('trend_history',m=>{const s=trendSeries(m.name);m.history_s.forEach((x,i)=>{
  s.x.push(x/3600);s.v.push(m.value[i]);s.lo.push(m.lo[i]);s.hi.push(m.hi[i]);});});
on('trend',m=>{for(const v of m.values){const s=trendSeries(v.name);s.x.push(m.history_s/3600);
  s.v.push(v.value);s.lo.push(v.lo);s.hi.push(v.hi);}});
on('estimate',m=>{if(m.ok)S.est.push(m);});on('bode',m=>{S.bode=m;});
on('sweep_point',m=>{S.sweep.push(m);});
on('outcome',m=>{S.outcome=m;es.close();document.body.dataset.stream='closed';});
setInterval(redraw,100);
window.addEventListener('resize',()=>{for(const k in C){const el=$(k);
  C[k].setSize({width:el.clientWidth,height:220});}});
$('stop').onclick=async()=>{const tok=$('token').value.trim();
  const r=await fetch('stop',{method:'POST',headers:{'X-Rig-Token':tok}});
  text('stopmsg',r.status===202?'stopping: the bias ramps back to baseline':
    'refused ('+r.status+'): the stop needs the token printed on the rig\'s console');
  document.body.dataset.stopStatus=r.status;};
)js";

constexpr const char* kBody = R"html(
<div id="banner"></div>
<div id="status"></div>
<div id="stopbox"><input id="token" type="password" size="34"
 placeholder="stop token (printed on the rig's console)" autocomplete="off">
<button id="stop">Stop</button><span id="stopmsg"></span></div>
<div class="grid">
<div class="card"><div id="c_dev"></div></div><div class="card"><div id="c_u"></div></div>
<div class="card commission"><div id="c_mag"></div></div><div class="card commission"><div id="c_ph"></div></div>
<div class="card commission"><div id="c_gain"></div></div><div class="card commission"><div id="c_fn_hz"></div></div>
<div class="card commission"><div id="c_zeta"></div></div><div class="card commission"><div id="c_delay_s"></div></div>
</div>
<div id="trendbox" style="display:none"><h2>Tracked parameters (rig monitor)</h2>
<div class="grid" id="trends"></div></div>
<div class="card"><h2>Events</h2><div id="events"></div></div>
)html";

}  // namespace

std::string live_page_html(const std::string& title) {
  return fmt::format(
      "<!doctype html><html><head><meta charset=\"utf-8\"><title>{0}</title>"
      "<meta name=\"viewport\" content=\"width=device-width\"><style>{1}</style><style>{2}"
      "</style><script>{3}</script></head><body><h1>{0}</h1>{4}<script>{5}</script>"
      "</body></html>",
      title, report::kUplotCss, kStyle, report::kUplotJs, kBody, kScript);
}

}  // namespace rig::live
