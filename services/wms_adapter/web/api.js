// The adapter's API as the page uses it: a session made from the bearer token (an HttpOnly cookie
// the page never sees, plus a CSRF token kept in memory only), JSON requests with plain error
// messages, and the SSE stream with reconnects.

/** What GET /v1/stream sends (docs/openapi.yaml). */
export const STREAM_EVENTS = ['snapshot', 'robots', 'task', 'risk', 'roadmap', 'releases', 'queues', 'proximity'];

/**
 * The URL of an API path ('/v1/...') for this page. The page lives at <prefix>/dashboard/ and the
 * API at <prefix>/v1/: resolved against the page, so the dashboard works behind a reverse proxy or
 * an ingress that serves the adapter under a path prefix.
 */
export function apiUrl(path) {
  return new URL('..' + path, window.location.href).href;
}

export class ApiError extends Error {
  constructor(status, message) {
    super(message);
    this.status = status;
  }
}

export class Api {
  constructor() {
    this.csrf = '';
  }

  /**
   * The current session: {auth: 'off' (no authentication) | 'session' | 'bearer', name, scopes},
   * or throws ApiError(401).
   */
  async session() {
    const body = await this.request('GET', '/v1/session');
    this.csrf = body.csrf || '';
    // No list (a server that does not say): offer everything; the server refuses what it must.
    const scopes = Array.isArray(body.scopes) ? body.scopes : ['read', 'submit', 'operate'];
    return { auth: body.auth, name: body.name || '', scopes };
  }

  /** Makes a session from the token: the token travels once, in a header, never in a URL. */
  async login(token) {
    const res = await fetch(apiUrl('/v1/session'), {
      method: 'POST',
      headers: { Authorization: 'Bearer ' + token },
      credentials: 'same-origin',
    });
    const body = await readJson(res);
    if (!res.ok) {
      throw new ApiError(res.status, res.status === 401 ? 'wrong token' : describe(res.status, body));
    }
    this.csrf = body.csrf;
  }

  async logout() {
    await this.request('DELETE', '/v1/session');
    this.csrf = '';
  }

  async request(method, path, body) {
    const headers = {};
    if (method !== 'GET') {
      headers['X-CSRF-Token'] = this.csrf;
    }
    if (body !== undefined) {
      headers['Content-Type'] = 'application/json';
    }
    let res;
    try {
      res = await fetch(apiUrl(path), {
        method,
        headers,
        credentials: 'same-origin',
        body: body === undefined ? undefined : JSON.stringify(body),
      });
    } catch (e) {
      throw new ApiError(0, 'the adapter is unreachable (' + e.message + ')');
    }
    const json = await readJson(res);
    if (!res.ok) {
      throw new ApiError(res.status, describe(res.status, json));
    }
    return json;
  }

  /**
   * Opens the stream. `handlers`: one per event name in STREAM_EVENTS (parsed data), state(text,
   * level) for the connection, unauthorized() when the session is gone. Reconnects by itself;
   * returns a closer.
   */
  stream(handlers) {
    let es = null;
    let closed = false;
    let retryTimer = 0;
    const open = () => {
      es = new EventSource(apiUrl('/v1/stream'));
      es.addEventListener('open', () => handlers.state('live', 'ok'));
      for (const name of STREAM_EVENTS) {
        es.addEventListener(name, (ev) => {
          let data;
          try {
            data = JSON.parse(ev.data);
          } catch {
            handlers.state('the adapter sent a malformed ' + name + ' message', 'warn');
            return;
          }
          handlers[name](data);
        });
      }
      es.addEventListener('error', async () => {
        if (closed) {
          return;
        }
        if (es.readyState === EventSource.CONNECTING) {
          handlers.state('connection lost — reconnecting…', 'bad');
          return;
        }
        // Closed for good (an HTTP error such as 401/429/503): find out why, then retry.
        es.close();
        try {
          await this.session();
          handlers.state('stream refused by the adapter — retrying in 2 s', 'bad');
        } catch (e) {
          if (e.status === 401) {
            handlers.unauthorized();
            return;
          }
          handlers.state(e.message + ' — retrying in 2 s', 'bad');
        }
        retryTimer = setTimeout(open, 2000);
      });
    };
    open();
    return () => {
      closed = true;
      clearTimeout(retryTimer);
      if (es) {
        es.close();
      }
    };
  }
}

async function readJson(res) {
  try {
    return await res.json();
  } catch {
    return {};
  }
}

/** A plain sentence for an error reply. */
export function describe(status, body) {
  const what = body && (body.message || (body.fields && body.fields.map((f) => f.path + ': ' + f.reason).join('; ')));
  const prefix = {
    400: 'refused',
    401: 'not logged in',
    403: 'forbidden',
    404: 'not found',
    409: 'conflict',
    429: 'the adapter is busy, try again',
    503: 'the fleet manager is unavailable',
  }[status] || 'HTTP ' + status;
  return what ? prefix + ': ' + what : prefix;
}
