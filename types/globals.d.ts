// Types of the page's globals, for `tsc --checkJs` (make lint); not loaded by the browser.

interface Window {
  /** The page's handle for the browser tests and the curious (page.js). */
  procfit: {
    client: import('../www/client.js').WorkerClient;
    REQUESTS: typeof import('../www/protocol.js').REQUESTS;
    state: import('../www/page.js').PageState;
    [more: string]: unknown;
  };
}
